// Move-only owners of a cuFFT plan and a CUDA event, for the batched GCC stage (candidates
// for gpu/core once another stage needs them). Failures come back as Status
// (gpu/core/cuda_status.h); destructors release and ignore errors.
#pragma once

#include <cuda_runtime_api.h>
#include <cufft.h>

#include <cstddef>
#include <string>
#include <utility>

#include "gpu/core/cuda_status.h"

namespace localizer::gpu {

// A move-only cufftHandle.
class CufftPlan {
 public:
  CufftPlan() = default;
  ~CufftPlan() {
    if (handle_ != CUFFT_PLAN_NULL) cufftDestroy(handle_);
  }
  CufftPlan(CufftPlan&& other) noexcept : handle_(std::exchange(other.handle_, CUFFT_PLAN_NULL)) {}
  CufftPlan& operator=(CufftPlan&& other) noexcept {
    std::swap(handle_, other.handle_);
    return *this;
  }
  CufftPlan(const CufftPlan&) = delete;
  CufftPlan& operator=(const CufftPlan&) = delete;

  // A 1-D real transform of size n over `batch` contiguous rows (basic layout: rows of n
  // reals, n/2 + 1 complex), on `stream`, without a work area of its own; *work_bytes is
  // what it needs (cufftSetWorkArea before each execution).
  static StatusOr<CufftPlan> Make(int n, cufftType type, long long batch, cudaStream_t stream,
                                  std::size_t* work_bytes) {
    CufftPlan plan;
    LOCALIZER_CUFFT_RETURN_IF_ERROR(cufftCreate(&plan.handle_), "cufftCreate");
    LOCALIZER_CUFFT_RETURN_IF_ERROR(cufftSetAutoAllocation(plan.handle_, 0), "cufftSetAutoAllocation");
    long long size = n;
    const std::string what = std::string("cufftMakePlanMany64(") + (type == CUFFT_R2C ? "R2C" : "C2R") +
                             ", n=" + std::to_string(n) + ", batch=" + std::to_string(batch) + ")";
    LOCALIZER_CUFFT_RETURN_IF_ERROR(
        cufftMakePlanMany64(plan.handle_, 1, &size, nullptr, 1, 0, nullptr, 1, 0, type, batch, work_bytes),
        what.c_str());
    LOCALIZER_CUFFT_RETURN_IF_ERROR(cufftSetStream(plan.handle_, stream), "cufftSetStream");
    return plan;
  }

  cufftHandle get() const { return handle_; }

 private:
  cufftHandle handle_ = CUFFT_PLAN_NULL;
};

// A move-only cudaEvent_t with timing.
class CudaEvent {
 public:
  CudaEvent() = default;
  ~CudaEvent() {
    if (event_ != nullptr) cudaEventDestroy(event_);
  }
  CudaEvent(CudaEvent&& other) noexcept : event_(std::exchange(other.event_, nullptr)) {}
  CudaEvent& operator=(CudaEvent&& other) noexcept {
    std::swap(event_, other.event_);
    return *this;
  }
  CudaEvent(const CudaEvent&) = delete;
  CudaEvent& operator=(const CudaEvent&) = delete;

  static StatusOr<CudaEvent> Create() {
    CudaEvent e;
    LOCALIZER_CUDA_RETURN_IF_ERROR(cudaEventCreate(&e.event_), "cudaEventCreate");
    return e;
  }
  cudaEvent_t get() const { return event_; }

 private:
  cudaEvent_t event_ = nullptr;
};

}  // namespace localizer::gpu
