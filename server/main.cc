// localizer-server: the localization service. `localizer-server --help` lists the flags.
// Exit codes: 0 after a clean shutdown (SIGTERM/SIGINT), 1 when it cannot start (address
// in use, ...), 2 for a usage error.
#include <pthread.h>

#include <csignal>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "engine/core/flags.h"
#include "engine/pipeline/backend.h"
#include "server/service/heap_settings.h"
#include "server/service/log.h"
#include "server/service/server.h"
#include "server/service/version.h"

namespace localizer::server {
namespace {

constexpr const char* kSummary =
    "Serves localizer.v1.Localizer over gRPC: sensor arrays stream sample blocks, the server\n"
    "measures TDOAs (GCC-PHAT), tracks each session's source and streams estimates back.\n"
    "Also serves grpc.health.v1 (NOT_SERVING while draining) and server reflection, and\n"
    "Prometheus metrics at http://METRICS-LISTEN/metrics (https:// with --metrics-tls-cert).\n"
    "SIGTERM or SIGINT drains and exits.";

Status WriteReadyFile(const std::string& path, const Server& server) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp);
    out << "{\"grpc_port\": " << server.grpc_port() << ", \"metrics_port\": " << server.metrics_port()
        << ", \"pid\": " << getpid() << "}\n";
    if (!out) return Unavailable("cannot write " + tmp);
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) return Unavailable("cannot rename " + tmp + " to " + path);
  return Status::Ok();
}

int Main(int argc, char** argv) {
  ServerOptions o;
  int max_block_samples = static_cast<int>(o.max_block_samples);
  bool version = false;
  FlagSet flags("localizer-server [flags]", kSummary);
  flags.String("listen", &o.listen, "HOST:PORT", "gRPC address (port 0: any free port; see --ready-file)");
  flags.String("metrics-listen", &o.metrics_listen, "HOST:PORT",
               "HTTP address of /metrics (Prometheus), / (live view) and /sessions (JSON); HTTPS with "
               "--metrics-tls-cert (\"\": off)");
  flags.String("backend", &o.backend, "auto|cpu|gpu",
               "compute backend for sessions that do not choose; gpu without a device refuses sessions");
  flags.Int("max-sessions", &o.max_sessions, "N", "sessions", "open sessions before RESOURCE_EXHAUSTED");
  flags.Int("workers", &o.workers, "N", "threads", "engine worker threads (0: one per core)");
  flags.Double("session-ttl", &o.session_ttl_s, "S", "s", "how long a session whose stream broke waits for a resume");
  flags.Double("session-idle-timeout", &o.session_idle_timeout_s, "S", "s",
               "an attached session that sends no block, IMU batch or scan for this long is closed "
               "(DEADLINE_EXCEEDED); 0: never");
  flags.Int("max-queue-blocks", &o.max_queued_requests, "N", "requests",
            "requests (blocks, IMU batches, scans, refusals) queued per session before reading pauses "
            "(backpressure)");
  flags.Int("max-block-samples", &max_block_samples, "N", "samples", "per channel per block");
  flags.Int("max-channels", &o.max_channels, "N", "sensors", "largest array accepted");
  flags.Int("max-particles", &o.max_particles, "N", "particles", "largest filter.particles accepted");
  flags.Int("max-message-bytes", &o.max_message_bytes, "N", "bytes", "largest gRPC message accepted (and sent)");
  flags.Int("max-tracks", &o.max_tracks, "N", "tracks",
            "detection sessions: most tracks held at once (default and ceiling of detections.max_tracks); its "
            "TrackList must fit in --max-message-bytes");
  flags.Int("max-scan-plots", &o.max_scan_plots, "N", "plots",
            "detection sessions: most plots in one scan (default and ceiling of detections.max_plots_per_scan); "
            "a larger scan is refused in-band");
  flags.Int("memory-budget-mib", &o.memory_budget_mib, "N", "MiB",
            "engine memory promised to sessions and Locate calls; what does not fit is RESOURCE_EXHAUSTED "
            "(0: 3/4 of the cgroup's or the machine's memory)");
  flags.Int("max-concurrent-locate", &o.max_concurrent_locate, "N", "calls",
            "Locate calls queued or running at once; more are RESOURCE_EXHAUSTED (0: one per worker)");
  flags.Int("max-streams-per-connection", &o.transport.max_streams_per_connection, "N", "streams",
            "concurrent RPCs on one HTTP/2 connection");
  flags.Int("grpc-memory-mib", &o.transport.grpc_memory_mib, "N", "MiB",
            "gRPC's own buffer memory (its resource quota; 0: unlimited)");
  flags.Double("max-connection-idle", &o.transport.connection_idle_s, "S", "s",
               "a connection without an RPC this long is sent GOAWAY (clients reconnect); 0: never");
  flags.Double("max-connection-age", &o.transport.connection_age_s, "S", "s",
               "connections are sent GOAWAY after this long, streams ending after a 30 s grace (resume continues "
               "them); 0: never");
  flags.Double("keepalive", &o.transport.keepalive_s, "S", "s",
               "ping a quiet connection after this long, drop it 20 s after an unanswered ping; 0: off");
  flags.Double("drain-timeout", &o.drain_timeout_s, "S", "s", "on SIGTERM, time allowed to finish in-flight work");
  flags.Double("memory-trim", &o.memory_trim_s, "S", "s",
               "hand the allocator's free pages back to the system this often (RSS follows use); 0: never");
  flags.Int("live-keep-finished", &o.live_keep_finished, "N", "sessions",
            "the live view (GET /, GET /sessions \"finished\") keeps this many ended sessions with their tracks, to "
            "view and replay (0: none; at most 256)");
  flags.Double("live-keep-finished-s", &o.live_keep_finished_s, "S", "s",
               "how long the live view keeps an ended session");
  flags.String("ready-file", &o.ready_file, "PATH",
               "once serving, write {\"grpc_port\", \"metrics_port\", \"pid\"} as JSON here (atomically)");
  flags.String("log-level", &o.log_level, "LEVEL", "debug | info | warn | error (logfmt lines on stderr)");
  flags.Double("gpu-batch-window-ms", &o.gpu_batch_window_ms, "MS", "ms",
               "GPU: longest a frame waits for other sessions' frames before a batch launches");
  flags.Int("gpu-max-batch", &o.gpu_max_batch, "N", "frames", "GPU: a batch launches as soon as this many wait");
  flags.Int("gpu-bank-mib", &o.gpu_bank_mib, "N", "MiB",
            "GPU: device memory for particles (0: 3/4 of free); a session beyond it gets RESOURCE_EXHAUSTED");
  flags.String("tls-cert", &o.tls_cert, "FILE",
               "PEM certificate chain: serve gRPC over TLS (with --tls-key; docs/SECURITY.md)");
  flags.String("tls-key", &o.tls_key, "FILE", "PEM private key of --tls-cert (unencrypted)");
  flags.String("tls-client-ca", &o.tls_client_ca, "FILE",
               "PEM CA certificates: require and verify client certificates signed by them (mutual TLS)");
  flags.String("metrics-tls-cert", &o.metrics_tls_cert, "FILE",
               "PEM certificate chain: serve --metrics-listen over HTTPS (with --metrics-tls-key; may be the "
               "--tls-cert file)");
  flags.String("metrics-tls-key", &o.metrics_tls_key, "FILE", "PEM private key of --metrics-tls-cert (unencrypted)");
  flags.String("metrics-tls-client-ca", &o.metrics_tls_client_ca, "FILE",
               "PEM CA certificates: HTTPS clients must present a certificate signed by them (mutual TLS)");
  flags.String("auth-token-file", &o.auth_token_file, "FILE",
               "'ROLE TOKEN' lines (ROLE client or operator, tokens >= 16 chars; '#' comments): every call "
               "needs 'authorization: Bearer TOKEN'; ListSessions, CloseSession and HTTP /sessions, / need "
               "operator");
  flags.Bool("version", &version, "print the version and exit");
  const Status parsed = flags.Parse(std::vector<std::string>(argv + 1, argv + argc));
  if (flags.help_requested()) {
    std::cout << flags.Usage();
    return 0;
  }
  if (!parsed.ok()) {
    std::cerr << "localizer-server: " << parsed.message() << "\nrun 'localizer-server --help' for the flags\n";
    return 2;
  }
  if (version) {
    std::cout << "localizer-server " << kLocalizerVersion << "\n";
    return 0;
  }
  o.max_block_samples = max_block_samples;
  if (const Status valid = o.Validate(); !valid.ok()) {
    std::cerr << "localizer-server: " << valid.message() << "\n";
    return 2;
  }

  ConfigureHeapForServing();  // before any thread starts (heap_settings.h)

  // Signals are taken by sigwait on this thread; every thread started later inherits the mask.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGTERM);
  sigaddset(&stop_signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);

  auto server = Server::Start(o);
  if (!server.ok()) {
    LogEvent("error", "start_failed", {{"status", server.status().ToString()}});
    std::cerr << "localizer-server: " << server.status().ToString() << "\n";
    return 1;
  }
  if (!o.ready_file.empty()) {
    if (const Status written = WriteReadyFile(o.ready_file, **server); !written.ok()) {
      std::cerr << "localizer-server: " << written.ToString() << "\n";
      return 1;
    }
  }
  int signal_number = 0;
  sigwait(&stop_signals, &signal_number);
  LogEvent("info", "signal", {{"signal", signal_number == SIGTERM ? "SIGTERM" : "SIGINT"}});
  (*server)->Shutdown();
  engine::SetGpuProvider(nullptr);  // stop the GPU dispatchers before static destruction
  return 0;
}

}  // namespace
}  // namespace localizer::server

int main(int argc, char** argv) { return localizer::server::Main(argc, argv); }
