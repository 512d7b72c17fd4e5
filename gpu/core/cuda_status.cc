#include "gpu/core/cuda_status.h"

#include <string>

namespace localizer::gpu {

Status FromCuda(cudaError_t result, const char* what) {
  if (result == cudaSuccess) return Status::Ok();
  const std::string message =
      std::string(what) + ": " + cudaGetErrorName(result) + " (" + cudaGetErrorString(result) + ")";
  switch (result) {
    case cudaErrorMemoryAllocation:
      return ResourceExhausted("GPU memory exhausted in " + message);
    case cudaErrorNoDevice:
    case cudaErrorInsufficientDriver:
    case cudaErrorInvalidDevice:
    case cudaErrorDevicesUnavailable:
    case cudaErrorNoKernelImageForDevice:
      return FailedPrecondition("GPU unusable in " + message);
    default:
      return Internal("GPU error in " + message);
  }
}

const char* CufftResultName(cufftResult result) {
  switch (result) {
    case CUFFT_SUCCESS:
      return "CUFFT_SUCCESS";
    case CUFFT_INVALID_PLAN:
      return "CUFFT_INVALID_PLAN";
    case CUFFT_ALLOC_FAILED:
      return "CUFFT_ALLOC_FAILED";
    case CUFFT_INVALID_TYPE:
      return "CUFFT_INVALID_TYPE";
    case CUFFT_INVALID_VALUE:
      return "CUFFT_INVALID_VALUE";
    case CUFFT_INTERNAL_ERROR:
      return "CUFFT_INTERNAL_ERROR";
    case CUFFT_EXEC_FAILED:
      return "CUFFT_EXEC_FAILED";
    case CUFFT_SETUP_FAILED:
      return "CUFFT_SETUP_FAILED";
    case CUFFT_INVALID_SIZE:
      return "CUFFT_INVALID_SIZE";
    case CUFFT_INVALID_DEVICE:
      return "CUFFT_INVALID_DEVICE";
    case CUFFT_NO_WORKSPACE:
      return "CUFFT_NO_WORKSPACE";
    case CUFFT_NOT_IMPLEMENTED:
      return "CUFFT_NOT_IMPLEMENTED";
    case CUFFT_NOT_SUPPORTED:
      return "CUFFT_NOT_SUPPORTED";
    default:
      return "CUFFT_UNKNOWN_ERROR";
  }
}

Status FromCufft(cufftResult result, const char* what) {
  if (result == CUFFT_SUCCESS) return Status::Ok();
  const std::string message = std::string(what) + ": " + CufftResultName(result);
  if (result == CUFFT_ALLOC_FAILED) return ResourceExhausted("GPU memory exhausted in " + message);
  return Internal("cuFFT error in " + message);
}

Status LastLaunchError(const char* kernel) {
  return FromCuda(cudaGetLastError(), (std::string("launch of ") + kernel).c_str());
}

}  // namespace localizer::gpu
