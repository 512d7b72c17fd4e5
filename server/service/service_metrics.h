// The service's metrics, registered once and cached as pointers for the hot paths.
//
//   localizer_stage_seconds{stage,backend}   histogram, 10 us .. 1 s:
//       tdoa    GCC-PHAT of one frame             filter  predict+update of one frame
//       queue   a block's wait for a worker       total   block received -> its estimates ready
//   localizer_blocks_total                   blocks accepted into a session
//   localizer_samples_total                  samples per channel accepted
//   localizer_estimates_total{backend}       estimates produced
//   localizer_rejections_total{reason}       blocks, IMU batches and scans refused (BlockRejected.reason)
//   localizer_sequence_gaps_total            sequence jumps (blocks lost upstream)
//   localizer_sessions{state}                sessions held now: attached | detached
//   localizer_sessions_opened_total{how}     open | resume
//   localizer_sessions_closed_total{reason}  finished | closed | expired | idle | replaced | shutdown
//   localizer_memory_budget_bytes{state}     used | limit: memory charged to sessions
//                                            and Locate calls, and the budget (memory_budget.h)
//   localizer_queue_depth_blocks             blocks waiting for a worker, all sessions
//   localizer_engine_cpu_seconds_total       worker-thread CPU inside Session::Process (the
//                                            rest of the process CPU is the service's overhead)
//   localizer_locate_requests_total{code}    one-shot Locate calls by status code
//   localizer_scans_total                    detection-session scans processed
//   localizer_scan_seconds{stage}            histogram: tracker (the track-while-scan cycle
//                                            of one scan), total (scan received -> tracks ready)
//   localizer_track_updates_total            tracks taken through a scan cycle (predict,
//                                            gate, update or coast), all detection sessions
//   localizer_auth_refusals_total{reason}   calls and HTTP requests refused by the bearer-token
//                                            check: missing | invalid | forbidden (auth.h)
//   localizer_http_tls_handshake_failures_total{reason}  HTTPS (--metrics-tls-cert) connections
//                                            closed in the handshake: timeout | closed |
//                                            certificate | protocol (tls_front.h); 0 without HTTPS
//   localizer_build_info{version,grpc_version,default_backend}  always 1
// Thread-safe: every pointer here is updated lock-free.
#pragma once

#include <string>

#include "server/metrics/registry.h"

namespace localizer::server {

struct StageHistograms {
  metrics::Histogram* tdoa = nullptr;
  metrics::Histogram* filter = nullptr;
  metrics::Histogram* queue = nullptr;
  metrics::Histogram* total = nullptr;
  metrics::Counter* estimates = nullptr;
};

class ServiceMetrics final {
 public:
  // Registers every family in `registry` (which must outlive this).
  static StatusOr<std::unique_ptr<ServiceMetrics>> Create(metrics::Registry* registry,
                                                          const std::string& default_backend);

  // Per backend ("cpu" or "gpu"); anything else is counted as "cpu".
  const StageHistograms& stages(const std::string& backend) const;
  metrics::Counter* rejections(const std::string& reason);  // looked up (mutex) per call
  metrics::Counter* sessions_closed(const std::string& reason);
  metrics::Counter* locate_requests(const std::string& code);
  // RefusalReason's "missing", "invalid" or "forbidden" (auth.h); exported at 0 from the start.
  metrics::Counter* auth_refusals(const std::string& reason);

  metrics::Counter* blocks = nullptr;
  metrics::Counter* samples = nullptr;
  metrics::Counter* gaps = nullptr;
  metrics::Counter* engine_cpu = nullptr;
  metrics::Counter* opened = nullptr;
  metrics::Counter* resumed = nullptr;
  metrics::Gauge* attached = nullptr;
  metrics::Gauge* detached = nullptr;
  metrics::Gauge* budget_used = nullptr;
  metrics::Gauge* budget_limit = nullptr;
  metrics::Gauge* queue_depth = nullptr;
  metrics::Counter* scans = nullptr;
  metrics::Counter* track_updates = nullptr;
  metrics::Histogram* scan_tracker = nullptr;
  metrics::Histogram* scan_total = nullptr;
  // Handed to the TLS front, which increments it per failure (label "reason").
  metrics::Family<metrics::Counter>* http_tls_handshake_failures = nullptr;

 private:
  ServiceMetrics() = default;
  StageHistograms cpu_, gpu_;
  metrics::Family<metrics::Counter>* rejections_ = nullptr;
  metrics::Family<metrics::Counter>* closed_ = nullptr;
  metrics::Family<metrics::Counter>* locate_ = nullptr;
  metrics::Family<metrics::Counter>* auth_refusals_ = nullptr;
};

}  // namespace localizer::server
