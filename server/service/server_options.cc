#include "server/service/server_options.h"

namespace localizer::server {

Status ServerOptions::Validate() const {
  if (listen.empty()) return InvalidArgument("listen is empty");
  if (backend != "auto" && backend != "cpu" && backend != "gpu") {
    return InvalidArgument("backend '" + backend + "' is not one of: auto, cpu, gpu");
  }
  if (max_sessions < 1) return InvalidArgument("max_sessions must be >= 1");
  if (workers < 0 || workers > 1024) return InvalidArgument("workers must be in [0, 1024] (0: one per core)");
  if (!(session_ttl_s >= 0.0)) return InvalidArgument("session_ttl_s must be >= 0");
  // Named as before the field was renamed (the flag is still --max-queue-blocks).
  if (max_queued_requests < 1) return InvalidArgument("max_queue_blocks must be >= 1");
  if (max_block_samples < 64) return InvalidArgument("max_block_samples must be >= 64");
  if (max_channels < 4) return InvalidArgument("max_channels must be >= 4");
  if (max_particles < 16) return InvalidArgument("max_particles must be >= 16");
  if (max_message_bytes < 1024) return InvalidArgument("max_message_bytes must be >= 1024");
  if (!(drain_timeout_s >= 0.0)) return InvalidArgument("drain_timeout_s must be >= 0");
  if (!(memory_trim_s >= 0.0 && memory_trim_s <= 86400.0)) {
    return InvalidArgument("memory_trim_s must be in [0, 86400] (0: never)");
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
  return Status::Ok();
}

}  // namespace localizer::server
