// A build without CUDA: the provider exists only to say why "gpu" is unavailable.
#include <memory>

#include "engine/pipeline/backend.h"
#include "gpu/backend/gpu_backend.h"
#include "gpu/backend/gpu_backend_options.h"

namespace localizer::gpu {
namespace {

class NoCudaProvider final : public engine::UnavailableBackendProvider {
 public:
  std::string UnavailableReason() const override {
    return "this build has no CUDA backend (nvcc was not found when it was configured)";
  }
};

}  // namespace

Status RegisterGpuBackend(const GpuBackendOptions& options) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  engine::SetGpuProvider(std::make_shared<NoCudaProvider>());
  return Status::Ok();
}

bool BuiltWithCuda() { return false; }
std::string DeviceName() { return ""; }
GpuBatchCounts BatchCounts() { return {}; }

}  // namespace localizer::gpu
