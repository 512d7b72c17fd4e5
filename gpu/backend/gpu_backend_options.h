// GpuBackendOptions::Validate, shared by the CUDA build and the stub.
#pragma once

#include <string>

#include "gpu/backend/gpu_backend.h"

namespace localizer::gpu {

inline Status GpuBackendOptions::Validate() const {
  if (!(batch_window_s >= 0.0 && batch_window_s <= 1.0)) {
    return InvalidArgument("gpu batch_window_s must be in [0, 1], got " + std::to_string(batch_window_s));
  }
  if (max_batch_frames < 1 || max_batch_frames > (1 << 16)) {
    return InvalidArgument("gpu max_batch_frames must be in [1, 65536], got " + std::to_string(max_batch_frames));
  }
  return Status::Ok();
}

}  // namespace localizer::gpu
