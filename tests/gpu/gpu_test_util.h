// Shared by the GPU tests: skip (with the probe's reason) where no device can be used.
#pragma once

#include <gtest/gtest.h>

#include "engine/pipeline/backend.h"
#include "gpu/backend/gpu_backend.h"

namespace localizer::gpu::testing {

// Registers the GPU backend; returns "" when a device can be used, else the reason.
inline std::string GpuSkipReason() {
  if (!BuiltWithCuda()) return "this build has no CUDA backend";
  static const Status registered = RegisterGpuBackend();
  if (!registered.ok()) return registered.message();
  return engine::GpuUnavailableReason();
}

}  // namespace localizer::gpu::testing

// Use first thing in a test body that needs a device.
#define LOCALIZER_SKIP_WITHOUT_GPU()                                                      \
  do {                                                                                    \
    const std::string gpu_skip_reason_ = ::localizer::gpu::testing::GpuSkipReason();      \
    if (!gpu_skip_reason_.empty()) GTEST_SKIP() << "no usable GPU: " << gpu_skip_reason_; \
  } while (false)
