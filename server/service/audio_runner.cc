#include "server/service/audio_runner.h"

#include "server/service/runner_util.h"
#include "wire/config_wire.h"
#include "wire/estimate_wire.h"
#include "wire/imu_wire.h"
#include "wire/stream_wire.h"

namespace localizer::server {

AudioRunner::AudioRunner(std::unique_ptr<engine::Session> session, ServiceMetrics* metrics)
    : session_(std::move(session)),
      metrics_(metrics),
      stages_(metrics->stages(session_->backend())),
      info_{"samples",
            engine::FilterKindName(session_->config().tracker.kind),
            session_->backend(),
            session_->sensor_count(),
            true,
            engine::ArrayShapeName(session_->shape().shape),
            engine::LocalizationName(session_->localization())},
      block_limits_{session_->sensor_count(), session_->config().max_block_samples} {}

WorkItem AudioRunner::DecodeBlock(const v1::SampleBlock& block, Clock::time_point received,
                                  wire::DecodedBlock* scratch) const {
  std::string reason;
  const Status status = wire::DecodeBlock(block, block_limits_, scratch, &reason);
  if (!status.ok()) return {Rejection{RequestKind::kBlock, block.sequence(), reason, status}, received};
  BlockWork work;
  work.sequence = block.sequence();
  work.samples_per_channel = scratch->view.samples_per_channel;
  work.samples = std::move(scratch->samples);
  return {std::move(work), received};
}

WorkItem AudioRunner::DecodeImu(const v1::ImuBatch& batch, Clock::time_point received) const {
  if (!session_->config().array_in_body_frame) return {NotMoving(batch.sequence()), received};
  auto decoded = wire::DecodeImuBatch(batch);
  if (!decoded.ok()) return {Rejection{RequestKind::kImu, batch.sequence(), "imu", decoded.status()}, received};
  return {ImuWork{batch.sequence(), std::move(decoded).value()}, received};
}

WorkItem AudioRunner::DecodeScan(const v1::Scan& scan, Clock::time_point received) const {
  return {Rejection{RequestKind::kScan, scan.sequence(), "not_detections",
                    FailedPrecondition("a scan for an audio session (open it with SessionConfig.detections)")},
          received};
}

void AudioRunner::Process(WorkItem& item, Clock::time_point started, TrackHistory* track,
                          std::vector<ResponsePtr>* out) {
  if (const auto* block = std::get_if<BlockWork>(&item.work))
    return ProcessBlock(*block, item.received, started, track, out);
  if (const auto* imu = std::get_if<ImuWork>(&item.work)) return ProcessImu(*imu, out);
}

void AudioRunner::ProcessImu(const ImuWork& imu, std::vector<ResponsePtr>* out) {
  // Ordering against the previous batch is the engine's check (the reader cannot know).
  Status status = session_->AddImu(imu.batch.samples);
  if (status.ok() && imu.batch.origin_m) status = session_->SetPlatformOrigin(*imu.batch.origin_m);
  if (!status.ok()) {
    Bump(metrics_->rejections("imu"));
    out->push_back(RejectionResponse({RequestKind::kImu, imu.sequence, "imu", status}));
  }
}

void AudioRunner::ProcessBlock(const BlockWork& block, Clock::time_point received, Clock::time_point started,
                               TrackHistory* track, std::vector<ResponsePtr>* out) {
  if (block.gap) {
    auto gap = std::make_shared<v1::TrackResponse>();
    wire::SequenceGapToProto(block.gap->previous_sequence, block.sequence, block.gap->missing_blocks,
                             block.gap->skipped_samples, gap->mutable_gap());
    out->push_back(std::move(gap));
  }
  Observe(stages_.queue, Seconds(started - received));
  if (block.skip_samples > 0) (void)session_->Skip(block.skip_samples);
  engine::BlockView view;
  view.sequence = block.sequence;
  view.channel_count = block_limits_.channel_count;
  view.samples_per_channel = block.samples_per_channel;
  view.samples = block.samples.data();
  estimates_.clear();
  const double cpu_start_s = ThreadCpuSeconds();
  const Status status = session_->Process(view, &estimates_);
  Bump(metrics_->engine_cpu, ThreadCpuSeconds() - cpu_start_s);
  if (!status.ok()) {
    // The reader validated the block; the engine refusing it is unexpected but answered.
    Bump(metrics_->rejections("engine"));
    out->push_back(RejectionResponse({RequestKind::kBlock, block.sequence, "engine", status}));
    return;
  }
  Bump(metrics_->blocks);
  Bump(metrics_->samples, static_cast<double>(block.samples_per_channel));
  const Clock::time_point done = Clock::now();
  for (const engine::Estimate& e : estimates_) {
    std::shared_ptr<v1::TrackResponse> response = estimate_pool().TakeEstimate();  // reused once the history is full
    v1::Estimate* wire_estimate = response->mutable_estimate();
    wire::EstimateToProto(e, session_->config().reference_sensor, session_->backend(), wire_estimate);
    wire_estimate->mutable_latency()->set_queue_s(Seconds(started - received));
    wire_estimate->mutable_latency()->set_total_s(Seconds(done - received));
    Observe(stages_.tdoa, e.timings.tdoa_s);
    Observe(stages_.filter, e.timings.filter_s);
    Observe(stages_.total, Seconds(done - received));
    Bump(stages_.estimates);
    track->Append(e);
    out->push_back(std::move(response));
  }
}

v1::SessionConfig AudioRunner::EffectiveConfig(const std::string& label) const {
  v1::SessionConfig effective = wire::ConfigToProto(session_->config(), label);
  effective.set_backend(info_.backend);
  return effective;
}

}  // namespace localizer::server
