// Everything localizer-server can be told, with defaults and units. `localizer-server
// --help` prints the same table; main.cc binds one flag per field.
#pragma once

#include <cstdint>
#include <string>

#include "engine/core/status.h"
#include "server/service/transport_limits.h"

namespace localizer::server {

struct ServerOptions {
  std::string listen = "127.0.0.1:50051";         // gRPC address; port 0 picks a free one
  std::string metrics_listen = "127.0.0.1:9464";  // /metrics HTTP address; "" disables it
  std::string backend = "auto";                   // default for sessions that leave it ""
  int max_sessions = 1024;                        // open sessions (attached or detached)
  int workers = 0;                                // engine threads; 0: one per core
                                                  // (with a GPU: one per session up
                                                  // to 1024, as they wait on batches)
  double session_ttl_s = 60.0;                    // a detached session waits this long
  double session_idle_timeout_s = 300.0;          // an attached session that sends nothing
                                                  // this long is closed; 0: never
  int max_queued_requests = 8;                    // requests (blocks, IMU batches, scans,
                                                  // refusals) queued per session before
                                                  // reading pauses (backpressure);
                                                  // flag --max-queue-blocks
  int64_t max_block_samples = 1 << 22;            // per channel per block (the message
                                                  // size limit usually binds first)
  int max_channels = 64;                          // sensors per array
  int max_particles = 1 << 20;                    // filter.particles allowed
  int max_message_bytes = 64 << 20;               // largest gRPC message accepted (and sent)
  int max_tracks = 10000;                         // detection sessions: tracks held at once
                                                  // (a TrackList of them must fit in
                                                  // max_message_bytes: ~370 B a track)
  int max_scan_plots = 65536;                     // detection sessions: plots in one scan
  int memory_budget_mib = 0;                      // engine memory promised to sessions and
                                                  // Locate calls (memory_budget.h); 0: 3/4
                                                  // of the cgroup's limit or the machine's
  int max_concurrent_locate = 0;                  // Locate calls queued or running at once;
                                                  // 0: one per worker
  TransportLimits transport;                      // gRPC connections (transport_limits.h)
  double drain_timeout_s = 10.0;                  // SIGTERM: time to finish in-flight work
  double memory_trim_s = 30.0;                    // hand the allocator's free pages back
                                                  // to the system this often; 0: never
  int live_keep_finished = 16;                    // the live view keeps this many ended
                                                  // sessions (finished_sessions.h); 0: none
  double live_keep_finished_s = 600.0;            // ... each for this long
  std::string ready_file;                         // written once serving: JSON with ports
  std::string log_level = "info";                 // debug | info | warn | error
  // GPU backend (gpu/backend/gpu_backend.h); ignored without a device.
  double gpu_batch_window_ms = 1.0;  // longest a frame waits for others
  int gpu_max_batch = 1024;          // frames (or filter steps) per launch
  int gpu_bank_mib = 0;              // particle memory; 0: 3/4 of free

  // Transport security and authentication (docs/SECURITY.md; server/service/auth.h).
  // Files are read once, at Start; unreadable or malformed ones stop the start with an error
  // naming the flag and the path.
  std::string tls_cert;         // PEM certificate chain; with tls_key, gRPC is served over TLS
  std::string tls_key;          // PEM private key of tls_cert
  std::string tls_client_ca;    // PEM CA certificates; set: every client must present a
                                // certificate they signed (mutual TLS); needs tls_cert
  std::string auth_token_file;  // "ROLE TOKEN" lines; set: every Localizer call needs a
                                // bearer token (Track/Locate: client or operator,
                                // ListSessions/CloseSession and HTTP /sessions, /: operator);
                                // "": no authentication
  // HTTPS for the HTTP side (metrics_listen), with its own files (they may name the same
  // ones as tls_*): set, civetweb moves to an ephemeral loopback port and a TLS front
  // (server/metrics/tls_front.h) listens on metrics_listen; needs metrics_listen.
  std::string metrics_tls_cert;       // PEM certificate chain; with metrics_tls_key: HTTPS
  std::string metrics_tls_key;        // PEM private key of metrics_tls_cert
  std::string metrics_tls_client_ca;  // PEM CA certificates; set: every HTTPS client must
                                      // present a certificate they signed (mutual TLS)

  Status Validate() const;  // INVALID_ARGUMENT naming the field
};

}  // namespace localizer::server
