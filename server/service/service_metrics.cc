#include "server/service/service_metrics.h"

#include <grpcpp/grpcpp.h>

#include "server/metrics/tls_front.h"
#include "server/service/version.h"

namespace localizer::server {
namespace {

template <typename T>
T* Series(metrics::Family<T>* family, const std::vector<std::string>& labels) {
  auto series = family->WithLabels(labels);
  return series.ok() ? *series : nullptr;
}

}  // namespace

StatusOr<std::unique_ptr<ServiceMetrics>> ServiceMetrics::Create(metrics::Registry* r,
                                                                 const std::string& default_backend) {
  std::unique_ptr<ServiceMetrics> m(new ServiceMetrics());
  auto stage = r->AddHistogram("localizer_stage_seconds",
                               "Wall time per stage: tdoa and filter per frame, queue per block, total from "
                               "block received to its estimates ready.",
                               {"stage", "backend"}, metrics::DefaultLatencyBucketsSeconds());
  if (!stage.ok()) return stage.status();
  auto estimates = r->AddCounter("localizer_estimates_total", "Estimates produced.", {"backend"});
  if (!estimates.ok()) return estimates.status();
  for (const char* backend : {"cpu", "gpu"}) {
    StageHistograms& s = std::string(backend) == "cpu" ? m->cpu_ : m->gpu_;
    s.tdoa = Series(*stage, {"tdoa", backend});
    s.filter = Series(*stage, {"filter", backend});
    s.queue = Series(*stage, {"queue", backend});
    s.total = Series(*stage, {"total", backend});
    s.estimates = Series(*estimates, {backend});
  }
  auto counter = [&](const char* name, const char* help) -> metrics::Counter* {
    auto family = r->AddCounter(name, help);
    return family.ok() ? Series(*family, {}) : nullptr;
  };
  m->blocks = counter("localizer_blocks_total", "Blocks accepted into a session.");
  m->samples = counter("localizer_samples_total", "Samples per channel accepted into sessions.");
  m->engine_cpu = counter("localizer_engine_cpu_seconds_total",
                          "Worker-thread CPU time spent inside the engine (TDOA and filter), seconds.");
  m->gaps = counter("localizer_sequence_gaps_total", "Sequence-number jumps: blocks lost upstream.");
  m->scans = counter("localizer_scans_total", "Detection-session scans processed.");
  m->track_updates =
      counter("localizer_track_updates_total", "Tracks taken through a scan cycle (predict, gate, update or coast).");
  auto scan = r->AddHistogram("localizer_scan_seconds",
                              "Detection sessions: tracker = the track-while-scan cycle of one scan, total = scan "
                              "received to its track list ready.",
                              {"stage"}, metrics::DefaultLatencyBucketsSeconds());
  if (!scan.ok()) return scan.status();
  m->scan_tracker = Series(*scan, {"tracker"});
  m->scan_total = Series(*scan, {"total"});
  auto rejections =
      r->AddCounter("localizer_rejections_total", "Blocks, IMU batches and scans refused, by reason.", {"reason"});
  if (!rejections.ok()) return rejections.status();
  m->rejections_ = *rejections;
  auto opened =
      r->AddCounter("localizer_sessions_opened_total", "Track streams that opened or resumed a session.", {"how"});
  if (!opened.ok()) return opened.status();
  m->opened = Series(*opened, {"open"});
  m->resumed = Series(*opened, {"resume"});
  auto closed = r->AddCounter("localizer_sessions_closed_total", "Sessions ended, by reason.", {"reason"});
  if (!closed.ok()) return closed.status();
  m->closed_ = *closed;
  auto sessions = r->AddGauge("localizer_sessions", "Sessions held now, by state.", {"state"});
  if (!sessions.ok()) return sessions.status();
  m->attached = Series(*sessions, {"attached"});
  m->detached = Series(*sessions, {"detached"});
  auto budget = r->AddGauge("localizer_memory_budget_bytes",
                            "Memory charged to sessions (engine state and resume history) and Locate calls (used), "
                            "and the budget (limit).",
                            {"state"});
  if (!budget.ok()) return budget.status();
  m->budget_used = Series(*budget, {"used"});
  m->budget_limit = Series(*budget, {"limit"});
  auto depth = r->AddGauge("localizer_queue_depth_blocks", "Blocks waiting for a worker, all sessions.");
  if (!depth.ok()) return depth.status();
  m->queue_depth = Series(*depth, {});
  auto locate = r->AddCounter("localizer_locate_requests_total", "One-shot Locate calls, by status code.", {"code"});
  if (!locate.ok()) return locate.status();
  m->locate_ = *locate;
  auto refusals = r->AddCounter("localizer_auth_refusals_total",
                                "gRPC calls and HTTP requests refused by the bearer-token check, by reason "
                                "(missing, invalid, forbidden).",
                                {"reason"});
  if (!refusals.ok()) return refusals.status();
  m->auth_refusals_ = *refusals;
  for (const char* reason : {"missing", "invalid", "forbidden"}) (void)m->auth_refusals(reason);
  auto handshakes =
      r->AddCounter("localizer_http_tls_handshake_failures_total",
                    "HTTPS connections to the HTTP side closed in the TLS handshake, by reason (timeout, closed, "
                    "certificate, protocol).",
                    {"reason"});
  if (!handshakes.ok()) return handshakes.status();
  m->http_tls_handshake_failures = *handshakes;
  for (const char* reason : metrics::kHandshakeFailureReasons) (void)Series(*handshakes, {reason});
  auto info = r->AddGauge("localizer_build_info", "Build and runtime facts; the value is always 1.",
                          {"version", "grpc_version", "default_backend"});
  if (!info.ok()) return info.status();
  if (auto* g = Series(*info, {kLocalizerVersion, grpc::Version(), default_backend})) g->Set(1.0);
  for (const char* reason : {"channel_count", "non_finite", "empty", "oversize", "bad_samples", "duplicate",
                             "out_of_order", "imu", "not_moving", "scan", "not_detections", "not_samples"}) {
    (void)m->rejections(reason);  // exported at 0 from the start, so rate() works at once
  }
  return m;
}

const StageHistograms& ServiceMetrics::stages(const std::string& backend) const {
  return backend == "gpu" ? gpu_ : cpu_;
}

metrics::Counter* ServiceMetrics::rejections(const std::string& reason) { return Series(rejections_, {reason}); }
metrics::Counter* ServiceMetrics::sessions_closed(const std::string& reason) { return Series(closed_, {reason}); }
metrics::Counter* ServiceMetrics::locate_requests(const std::string& code) { return Series(locate_, {code}); }
metrics::Counter* ServiceMetrics::auth_refusals(const std::string& reason) { return Series(auth_refusals_, {reason}); }

}  // namespace localizer::server
