#include "server/service/server_options.h"

#include <cstdint>
#include <string>
#include <utility>

#include "server/service/finished_sessions.h"
#include "wire/scan_wire.h"

namespace localizer::server {

Status ServerOptions::Validate() const {
  if (listen.empty()) return InvalidArgument("listen is empty");
  if (backend != "auto" && backend != "cpu" && backend != "gpu") {
    return InvalidArgument("backend '" + backend + "' is not one of: auto, cpu, gpu");
  }
  if (max_sessions < 1) return InvalidArgument("max_sessions must be >= 1");
  if (workers < 0 || workers > 1024) return InvalidArgument("workers must be in [0, 1024] (0: one per core)");
  if (!(session_ttl_s >= 0.0)) return InvalidArgument("session_ttl_s must be >= 0");
  if (!(session_idle_timeout_s >= 0.0 && session_idle_timeout_s <= 1e9)) {
    return InvalidArgument("session_idle_timeout_s must be in [0, 1e9] (0: never)");
  }
  // Named as before the field was renamed (the flag is still --max-queue-blocks).
  if (max_queued_requests < 1) return InvalidArgument("max_queue_blocks must be >= 1");
  if (max_block_samples < 64) return InvalidArgument("max_block_samples must be >= 64");
  if (max_channels < 4) return InvalidArgument("max_channels must be >= 4");
  if (max_particles < 16) return InvalidArgument("max_particles must be >= 16");
  if (max_message_bytes < 1024) return InvalidArgument("max_message_bytes must be >= 1024");
  if (max_tracks < 1) return InvalidArgument("max_tracks must be >= 1");
  if (max_scan_plots < 1) return InvalidArgument("max_scan_plots must be >= 1");
  // A detection session's answer must always be sendable: a stream whose TrackList exceeds
  // the send limit ends RESOURCE_EXHAUSTED, and so would every resume.
  if (const int64_t bytes = wire::MaxTrackListBytes(max_tracks); bytes > max_message_bytes) {
    return InvalidArgument("max_tracks " + std::to_string(max_tracks) + " allows a TrackList of up to " +
                           std::to_string(bytes) + " bytes, above max_message_bytes " +
                           std::to_string(max_message_bytes) + ": lower --max-tracks or raise --max-message-bytes");
  }
  if (memory_budget_mib < 0) return InvalidArgument("memory_budget_mib must be >= 0 (0: from the machine)");
  if (max_concurrent_locate < 0) return InvalidArgument("max_concurrent_locate must be >= 0 (0: one per worker)");
  if (transport.max_streams_per_connection < 1) return InvalidArgument("max_streams_per_connection must be >= 1");
  if (transport.grpc_memory_mib < 0) return InvalidArgument("grpc_memory_mib must be >= 0 (0: unlimited)");
  for (const auto& [name, value] :
       {std::pair<const char*, double>{"max_connection_idle_s", transport.connection_idle_s},
        {"max_connection_age_s", transport.connection_age_s},
        {"keepalive_s", transport.keepalive_s}}) {
    if (!(value >= 0.0 && value <= 2e6)) return InvalidArgument(std::string(name) + " must be in [0, 2e6] (0: off)");
  }
  if (!(drain_timeout_s >= 0.0)) return InvalidArgument("drain_timeout_s must be >= 0");
  if (!(memory_trim_s >= 0.0 && memory_trim_s <= 86400.0)) {
    return InvalidArgument("memory_trim_s must be in [0, 86400] (0: never)");
  }
  if (live_keep_finished < 0 || live_keep_finished > static_cast<int>(FinishedSessions::kMaxKeep)) {
    return InvalidArgument("live_keep_finished must be in [0, " + std::to_string(FinishedSessions::kMaxKeep) +
                           "] (0: none)");
  }
  if (!(live_keep_finished_s >= 0.0 && live_keep_finished_s <= 86400.0)) {
    return InvalidArgument("live_keep_finished_s must be in [0, 86400]");
  }
  if (log_level != "debug" && log_level != "info" && log_level != "warn" && log_level != "error") {
    return InvalidArgument("log_level '" + log_level + "' is not one of: debug, info, warn, error");
  }
  if (!(gpu_batch_window_ms >= 0.0 && gpu_batch_window_ms <= 1000.0)) {
    return InvalidArgument("gpu_batch_window_ms must be in [0, 1000]");
  }
  if (gpu_max_batch < 1 || gpu_max_batch > 65536) return InvalidArgument("gpu_max_batch must be in [1, 65536]");
  if (gpu_bank_mib < 0) return InvalidArgument("gpu_bank_mib must be >= 0 (0: 3/4 of free device memory)");
  if (tls_cert.empty() != tls_key.empty()) {
    return InvalidArgument("tls_cert and tls_key go together (--tls-cert and --tls-key: both or neither)");
  }
  if (!tls_client_ca.empty() && tls_cert.empty()) {
    return InvalidArgument("tls_client_ca needs tls_cert and tls_key (mutual TLS is TLS plus client certificates)");
  }
  if (metrics_tls_cert.empty() != metrics_tls_key.empty()) {
    return InvalidArgument(
        "metrics_tls_cert and metrics_tls_key go together (--metrics-tls-cert and --metrics-tls-key: both or "
        "neither)");
  }
  if (!metrics_tls_client_ca.empty() && metrics_tls_cert.empty()) {
    return InvalidArgument(
        "metrics_tls_client_ca needs metrics_tls_cert and metrics_tls_key (mutual TLS is TLS plus client "
        "certificates)");
  }
  if (!metrics_tls_cert.empty() && metrics_listen.empty()) {
    return InvalidArgument("metrics_tls_cert needs metrics_listen (--metrics-listen \"\" turns the HTTP side off)");
  }
  return Status::Ok();
}

}  // namespace localizer::server
