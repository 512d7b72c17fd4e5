#include "gpu/core/device.h"

#include <cuda_runtime_api.h>

namespace localizer::gpu {
namespace {

struct Probe {
  std::string reason;
  DeviceInfo info;
};

Probe RunProbe() {
  Probe probe;
  int count = 0;
  const cudaError_t result = cudaGetDeviceCount(&count);
  if (result != cudaSuccess) {
    probe.reason =
        std::string("cudaGetDeviceCount: ") + cudaGetErrorString(result) + " (" + cudaGetErrorName(result) + ")";
    return probe;
  }
  if (count < 1) {
    probe.reason = "no CUDA device found (cudaGetDeviceCount returned 0)";
    return probe;
  }
  cudaDeviceProp props{};
  const cudaError_t prop_result = cudaGetDeviceProperties(&props, 0);
  if (prop_result != cudaSuccess) {
    probe.reason = std::string("cudaGetDeviceProperties: ") + cudaGetErrorString(prop_result);
    return probe;
  }
  probe.info.name = props.name;
  probe.info.compute_major = props.major;
  probe.info.compute_minor = props.minor;
  probe.info.multiprocessors = props.multiProcessorCount;
  probe.info.total_memory_bytes = props.totalGlobalMem;
  // Creating the context here makes a kernel image mismatch show up now, not mid-stream.
  const cudaError_t init = cudaFree(nullptr);
  if (init != cudaSuccess) {
    probe.reason = std::string("CUDA context creation failed: ") + cudaGetErrorString(init);
  }
  return probe;
}

const Probe& Cached() {
  static const Probe probe = RunProbe();
  return probe;
}

}  // namespace

const std::string& DeviceUnavailableReason() { return Cached().reason; }
const DeviceInfo& Device() { return Cached().info; }

}  // namespace localizer::gpu
