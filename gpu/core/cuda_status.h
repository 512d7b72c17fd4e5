// CUDA and cuFFT results as localizer Status values. Every call into the toolkit
// goes through one of these, so a device error reaches the caller (and the client) as a
// Status naming the call — a server never exits because of a GPU error.
//
//   LOCALIZER_CUDA_RETURN_IF_ERROR(cudaMalloc(&p, bytes), "cudaMalloc(bank)");
//
// Out-of-memory results (cudaErrorMemoryAllocation, CUFFT_ALLOC_FAILED) map to
// RESOURCE_EXHAUSTED; a missing or unusable device (no device, insufficient driver) to
// FAILED_PRECONDITION; everything else to INTERNAL.
#pragma once

#include <cuda_runtime_api.h>
#include <cufft.h>

#include "engine/core/status.h"

namespace localizer::gpu {

Status FromCuda(cudaError_t result, const char* what);
Status FromCufft(cufftResult result, const char* what);

// The error a kernel launch left behind (cudaGetLastError), as a Status.
Status LastLaunchError(const char* kernel);

const char* CufftResultName(cufftResult result);

}  // namespace localizer::gpu

#define LOCALIZER_GPU_CHECK_IMPL_(status_expr)       \
  do {                                               \
    ::localizer::Status gpu_status_ = (status_expr); \
    if (!gpu_status_.ok()) return gpu_status_;       \
  } while (false)

// Returns the failure of a CUDA runtime call as a Status from the enclosing function.
#define LOCALIZER_CUDA_RETURN_IF_ERROR(call, what) LOCALIZER_GPU_CHECK_IMPL_(::localizer::gpu::FromCuda((call), (what)))
#define LOCALIZER_CUFFT_RETURN_IF_ERROR(call, what) \
  LOCALIZER_GPU_CHECK_IMPL_(::localizer::gpu::FromCufft((call), (what)))
// After a <<<...>>> launch: configuration errors surface here, not at the next sync.
#define LOCALIZER_LAUNCH_RETURN_IF_ERROR(kernel) LOCALIZER_GPU_CHECK_IMPL_(::localizer::gpu::LastLaunchError(kernel))
