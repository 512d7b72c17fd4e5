#include "gpu/backend/gpu_tdoa_estimator.h"

#include <cstring>
#include <string>

#include "gpu/tdoa/frame_overlap.h"

namespace localizer::gpu {

StatusOr<std::unique_ptr<GpuTdoaEstimator>> GpuTdoaEstimator::Create(std::shared_ptr<GpuRuntime> runtime,
                                                                     const engine::ArrayGeometry& array,
                                                                     const engine::GccOptions& options) {
  auto plan = GccPlan::Create(array, options);
  if (!plan.ok()) return plan.status();
  auto staging = PinnedBuffer<float>::Allocate(static_cast<std::size_t>(plan->channels()) * options.frame_samples);
  if (!staging.ok()) return staging.status();
  // The newest frame is all a job reads back (sample_ring.cuh: capacity F).
  auto ring = SampleRing::Create(plan->channels(), options.frame_samples);
  if (!ring.ok()) return ring.status();
  return std::unique_ptr<GpuTdoaEstimator>(new GpuTdoaEstimator(std::move(runtime), std::move(plan).value(),
                                                                std::move(staging).value(), std::move(ring).value()));
}

GpuTdoaEstimator::GpuTdoaEstimator(std::shared_ptr<GpuRuntime> runtime, GccPlan plan, PinnedBuffer<float> staging,
                                   SampleRing ring)
    : runtime_(std::move(runtime)), plan_(std::move(plan)), staging_(std::move(staging)), ring_(std::move(ring)) {
  runtime_->AddProducer(GpuRuntime::Stage::kGcc);
}

GpuTdoaEstimator::~GpuTdoaEstimator() { runtime_->RemoveProducer(GpuRuntime::Stage::kGcc); }

Status GpuTdoaEstimator::Estimate(const float* frame, int frame_samples, double t_s, engine::Measurement* out) {
  if (frame == nullptr) return InvalidArgument("frame is null");
  if (out == nullptr) return InvalidArgument("out (the Measurement to fill) is null");
  const int expected = plan_.options().frame_samples;
  if (frame_samples != expected) {
    return InvalidArgument("frame_samples is " + std::to_string(frame_samples) +
                           "; the estimator was created for frame_samples = " + std::to_string(expected));
  }
  // The samples the ring lacks: the staging buffer still holds the frame the ring ends with.
  int fresh = expected;
  if (ring_.valid()) {
    fresh = NewSampleCount(staging_.data(), frame, plan_.channels(), expected, hop_hint_);
    if (fresh < expected) hop_hint_ = fresh;
  }
  // Non-finite samples are found while the batch measures the frame (GccJob::status).
  std::memcpy(staging_.data(), frame, staging_.bytes());
  GccQueueJob job{GccJob{&plan_, staging_.data(), t_s, out}, Status::Ok()};
  job.job.frame_pinned = true;
  job.job.ring = &ring_;
  job.job.ring_new_samples = fresh;
  job.job.tails = &tails_;
  const int64_t total_before = ring_.total();
  runtime_->RunGcc(&job);
  // Unless the batch appended this frame's samples (whatever the frame's own outcome), the
  // ring no longer ends with the staged frame: the next frame is sent whole.
  if (!ring_.valid() || ring_.total() != total_before + fresh) ring_.Invalidate();
  if (job.status.ok()) FinishCandidates(plan_, tails_, out, &extrema_);
  return job.status;
}

}  // namespace localizer::gpu
