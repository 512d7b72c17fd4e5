#include "server/service/detection_runner.h"

#include <string>

#include "server/service/runner_util.h"
#include "wire/config_wire.h"
#include "wire/scan_wire.h"

namespace localizer::server {

DetectionRunner::DetectionRunner(std::unique_ptr<engine::ScanSession> scans, ServiceMetrics* metrics)
    : scans_(std::move(scans)), metrics_(metrics), info_{"detections", "tws", "cpu", 0, false, "", ""} {}

WorkItem DetectionRunner::DecodeBlock(const v1::SampleBlock& block, Clock::time_point received,
                                      wire::DecodedBlock* /*scratch*/) const {
  return {Rejection{RequestKind::kBlock, block.sequence(), "not_samples",
                    FailedPrecondition("a sample block for a detection session (it takes scans)")},
          received};
}

WorkItem DetectionRunner::DecodeImu(const v1::ImuBatch& batch, Clock::time_point received) const {
  return {NotMoving(batch.sequence()), received};
}

WorkItem DetectionRunner::DecodeScan(const v1::Scan& scan, Clock::time_point received) const {
  // Refused before decoding: an oversized scan costs nothing past its parse.
  const int max_plots = scans_->config().tws.max_plots_per_scan;
  if (scan.detections_size() > max_plots) {
    return {Rejection{RequestKind::kScan, scan.sequence(), "scan",
                      InvalidArgument("scan.detections has " + std::to_string(scan.detections_size()) +
                                      " plots; this session allows at most " + std::to_string(max_plots) +
                                      " (detections.max_plots_per_scan)")},
            received};
  }
  auto decoded = wire::DecodeScan(scan);
  if (!decoded.ok()) return {Rejection{RequestKind::kScan, scan.sequence(), "scan", decoded.status()}, received};
  return {ScanWork{scan.sequence(), std::move(decoded).value()}, received};
}

void DetectionRunner::Process(WorkItem& item, Clock::time_point /*started*/, TrackHistory* track,
                              std::vector<ResponsePtr>* out) {
  const auto* work = std::get_if<ScanWork>(&item.work);
  if (work == nullptr) return;  // DecodeScan makes the only work this runner processes
  engine::ScanResult result;
  const double cpu_start_s = ThreadCpuSeconds();
  const Status status = scans_->Process(work->scan, &result);
  Bump(metrics_->engine_cpu, ThreadCpuSeconds() - cpu_start_s);
  if (!status.ok()) {  // out of time order, or a plot the tracker refuses
    Bump(metrics_->rejections("scan"));
    out->push_back(RejectionResponse({RequestKind::kScan, work->sequence, "scan", status}));
    return;
  }
  auto response = std::make_shared<v1::TrackResponse>();
  v1::TrackList* list = response->mutable_tracks();
  wire::TrackListToProto(result, work->sequence, list);
  const double total_s = Seconds(Clock::now() - item.received);
  list->set_total_s(total_s);
  Bump(metrics_->scans);
  Bump(metrics_->track_updates, static_cast<double>(result.summary.track_updates));
  Observe(metrics_->scan_tracker, result.process_s);
  Observe(metrics_->scan_total, total_s);
  track->SetTargets(result.tracks);
  out->push_back(std::move(response));
}

v1::SessionConfig DetectionRunner::EffectiveConfig(const std::string& label) const {
  v1::SessionConfig effective = wire::ConfigToProto(scans_->config(), label);
  effective.set_backend(info_.backend);
  return effective;
}

}  // namespace localizer::server
