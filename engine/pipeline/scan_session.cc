#include "engine/pipeline/scan_session.h"

#include <chrono>

namespace localizer::engine {

StatusOr<std::unique_ptr<ScanSession>> ScanSession::Create(const DetectionSessionConfig& config) {
  LOCALIZER_RETURN_IF_ERROR(config.Validate());
  auto tracker = tws::TwsTracker::Create(config.tws);
  if (!tracker.ok()) return tracker.status();
  return std::unique_ptr<ScanSession>(new ScanSession(config, std::move(tracker).value()));
}

Status ScanSession::Process(const Scan& scan, ScanResult* out) {
  const auto start = std::chrono::steady_clock::now();
  tws::ScanSummary summary;
  LOCALIZER_RETURN_IF_ERROR(tracker_->Process(scan, &summary));
  out->scan_index = scans_++;
  out->time_s = scan.time_s;
  tracker_->Tracks(&out->tracks, /*include_tentative=*/true);
  out->summary = summary;
  out->process_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return Status::Ok();
}

}  // namespace localizer::engine
