// engine::TdoaEstimator on the GPU: the CPU estimator's contract (gcc_phat.h: same
// validation, same Measurement fields, results equal within float tolerance), computed in
// the shared GCC batch of whatever sessions submit frames within the batching window.
// Estimate copies the frame into the estimator's own pinned buffer (on the session's thread,
// so many sessions' copies run in parallel and the device reads the frame in place), then
// blocks until its batch ran. Internal to gpu/backend.
//
// Each sample crosses the bus once: the session's newest frame also lives in a device ring
// (gpu/tdoa/sample_ring.h), and Estimate finds how many samples at the end of the new frame
// are new (gpu/tdoa/frame_overlap.h: the previous frame, still in the pinned buffer, is
// compared bit for bit with the new one's start), so the job appends only those and the
// frame is read from the ring. With the session's 50 % hop that halves the bytes per frame;
// a frame that does not continue the previous one (the first, one after a gap or after
// despiking changed the overlap, one after a device error) is sent whole. The frame the
// kernels read is the given frame bit for bit either way, so results do not change.
#pragma once

#include <memory>
#include <vector>

#include "engine/array/array_geometry.h"
#include "engine/tdoa/gcc_phat.h"
#include "gpu/backend/gpu_runtime.h"
#include "gpu/core/device_buffer.h"
#include "gpu/tdoa/gcc_batch.h"
#include "gpu/tdoa/sample_ring.h"

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
  GpuTdoaEstimator(std::shared_ptr<GpuRuntime> runtime, GccPlan plan, PinnedBuffer<float> staging, SampleRing ring);
  std::shared_ptr<GpuRuntime> runtime_;
  GccPlan plan_;
  PinnedBuffer<float> staging_;  // channels * frame_samples: this session's (last) frame
  SampleRing ring_;              // the same frame on the device (capacity frame_samples)
  int hop_hint_ = 0;             // the last overlap found: the framer's hop
  // The candidates are picked here, on the session's thread, not on the dispatcher's.
  std::vector<GccPairTail> tails_;
  std::vector<engine::WindowExtremum> extrema_;
};

}  // namespace localizer::gpu
