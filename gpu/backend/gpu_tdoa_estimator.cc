#include "gpu/backend/gpu_tdoa_estimator.h"

#include <cstring>
#include <string>

namespace localizer::gpu {

StatusOr<std::unique_ptr<GpuTdoaEstimator>> GpuTdoaEstimator::Create(std::shared_ptr<GpuRuntime> runtime,
                                                                     const engine::ArrayGeometry& array,
                                                                     const engine::GccOptions& options) {
  auto plan = GccPlan::Create(array, options);
  if (!plan.ok()) return plan.status();
  auto staging = PinnedBuffer<float>::Allocate(static_cast<std::size_t>(plan->channels()) * options.frame_samples);
  if (!staging.ok()) return staging.status();
  return std::unique_ptr<GpuTdoaEstimator>(
      new GpuTdoaEstimator(std::move(runtime), std::move(plan).value(), std::move(staging).value()));
}

GpuTdoaEstimator::GpuTdoaEstimator(std::shared_ptr<GpuRuntime> runtime, GccPlan plan, PinnedBuffer<float> staging)
    : runtime_(std::move(runtime)), plan_(std::move(plan)), staging_(std::move(staging)) {
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
  // Non-finite samples are found while the batch copies the frame (GccJob::status).
  std::memcpy(staging_.data(), frame, staging_.bytes());
  GccQueueJob job{GccJob{&plan_, staging_.data(), t_s, out}, Status::Ok()};
  job.job.frame_pinned = true;
  runtime_->RunGcc(&job);
  return job.status;
}

}  // namespace localizer::gpu
