// engine::TdoaEstimator on the GPU: the CPU estimator's contract (gcc_phat.h: same
// validation, same Measurement fields, results equal within float tolerance), computed in
// the shared GCC batch of whatever sessions submit frames within the batching window.
// Estimate copies the frame into the estimator's own pinned buffer (on the session's thread,
// so many sessions' copies run in parallel and the device reads the frame in place), then
// blocks until its batch ran. Internal to gpu/backend.
#pragma once

#include <memory>

#include "engine/array/array_geometry.h"
#include "engine/tdoa/gcc_phat.h"
#include "gpu/backend/gpu_runtime.h"
#include "gpu/core/device_buffer.h"

namespace localizer::gpu {

class GpuTdoaEstimator final : public engine::TdoaEstimator {
 public:
  // INVALID_ARGUMENT as GccPhatEstimator::Create.
  static StatusOr<std::unique_ptr<GpuTdoaEstimator>> Create(std::shared_ptr<GpuRuntime> runtime,
                                                            const engine::ArrayGeometry& array,
                                                            const engine::GccOptions& options);
  // INVALID_ARGUMENT as GccPhatEstimator::Estimate; device errors as their Status (out is
  // then unspecified).
  Status Estimate(const float* frame, int frame_samples, double t_s, engine::Measurement* out) override;
  ~GpuTdoaEstimator() override;

 private:
  GpuTdoaEstimator(std::shared_ptr<GpuRuntime> runtime, GccPlan plan, PinnedBuffer<float> staging);
  std::shared_ptr<GpuRuntime> runtime_;
  GccPlan plan_;
  PinnedBuffer<float> staging_;  // channels * frame_samples: this session's frame
};

}  // namespace localizer::gpu
