// A build without CUDA: the provider exists only to say why "gpu" is unavailable.
#include <memory>

#include "engine/pipeline/backend.h"
#include "gpu/backend/gpu_backend.h"
#include "gpu/backend/gpu_backend_options.h"

namespace localizer::gpu {
namespace {

class NoCudaProvider final : public engine::BackendProvider {
 public:
  std::string UnavailableReason() const override {
    return "this build has no CUDA backend (nvcc was not found when it was configured)";
  }
  StatusOr<std::unique_ptr<engine::TdoaEstimator>> MakeEstimator(const engine::ArrayGeometry&,
                                                                 const engine::GccOptions&) override {
    return FailedPrecondition(UnavailableReason());
  }
  StatusOr<std::unique_ptr<engine::Tracker>> MakeTracker(const engine::ArrayGeometry&,
                                                         const engine::ParticleFilterOptions&) override {
    return FailedPrecondition(UnavailableReason());
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
