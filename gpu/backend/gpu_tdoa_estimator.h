// engine::TdoaEstimator on the GPU: the CPU estimator's contract (gcc_phat.h: same
// validation, same Measurement fields, results equal within float tolerance), computed in
// the shared GCC batch of whatever sessions submit frames within the batching window.
// Estimate blocks the calling thread until its batch ran. Internal to gpu/backend.
#pragma once

#include <memory>

#include "engine/array/array_geometry.h"
#include "engine/tdoa/gcc_phat.h"
#include "gpu/backend/gpu_runtime.h"

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

 private:
  GpuTdoaEstimator(std::shared_ptr<GpuRuntime> runtime, GccPlan plan)
      : runtime_(std::move(runtime)), plan_(std::move(plan)) {}
  std::shared_ptr<GpuRuntime> runtime_;
  GccPlan plan_;
};

}  // namespace localizer::gpu
