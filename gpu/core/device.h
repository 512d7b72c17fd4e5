// Is there a CUDA device this process can use, and what is it.
#pragma once

#include <cstddef>
#include <string>

namespace localizer::gpu {

struct DeviceInfo {
  std::string name;  // e.g. "NVIDIA H100 80GB HBM3"
  int compute_major = 0;
  int compute_minor = 0;
  int multiprocessors = 0;
  std::size_t total_memory_bytes = 0;
};

// "" when device 0 can be used; otherwise why not, e.g. "cudaGetDeviceCount: CUDA driver
// version is insufficient for CUDA runtime version (cudaErrorInsufficientDriver)" on a
// machine without the driver, or "no CUDA device found". Probed once per process (the
// first call takes the CUDA runtime's start-up time, ~0.1-1 s) and cached.
const std::string& DeviceUnavailableReason();

// Device 0's properties; only meaningful when DeviceUnavailableReason() is "".
const DeviceInfo& Device();

}  // namespace localizer::gpu
