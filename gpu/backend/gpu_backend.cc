#include "gpu/backend/gpu_backend.h"

#include <memory>
#include <mutex>

#include "engine/pipeline/backend.h"
#include "gpu/backend/gpu_backend_options.h"
#include "gpu/backend/gpu_particle_filter.h"
#include "gpu/backend/gpu_runtime.h"
#include "gpu/backend/gpu_tdoa_estimator.h"
#include "gpu/core/device.h"

namespace localizer::gpu {
namespace {

// The runtime the registered provider made, for BatchCounts (weak: sessions and the
// provider own it).
std::mutex runtime_mutex;
std::weak_ptr<GpuRuntime> current_runtime;

class CudaProvider final : public engine::BackendProvider {
 public:
  explicit CudaProvider(const GpuBackendOptions& options) : options_(options) {}

  std::string UnavailableReason() const override { return DeviceUnavailableReason(); }

  StatusOr<std::unique_ptr<engine::TdoaEstimator>> MakeEstimator(const engine::ArrayGeometry& array,
                                                                 const engine::GccOptions& options) override {
    auto runtime = Runtime();
    if (!runtime.ok()) return runtime.status();
    auto estimator = GpuTdoaEstimator::Create(*runtime, array, options);
    if (!estimator.ok()) return estimator.status();
    return std::unique_ptr<engine::TdoaEstimator>(std::move(estimator).value());
  }

  StatusOr<std::unique_ptr<engine::Tracker>> MakeTracker(const engine::ArrayGeometry& array,
                                                         const engine::ParticleFilterOptions& options) override {
    auto runtime = Runtime();
    if (!runtime.ok()) return runtime.status();
    auto tracker = GpuParticleFilter::Create(*runtime, array, options);
    if (!tracker.ok()) return tracker.status();
    return std::unique_ptr<engine::Tracker>(std::move(tracker).value());
  }

 private:
  // Made by the first GPU session; a failure is reported to that session and retried by
  // the next (a transient out-of-memory should not disable the GPU for good).
  StatusOr<std::shared_ptr<GpuRuntime>> Runtime() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (runtime_) return runtime_;
    const std::string& reason = DeviceUnavailableReason();
    if (!reason.empty()) return FailedPrecondition("backend gpu requested but unavailable: " + reason);
    auto made = GpuRuntime::Create(options_);
    if (!made.ok()) return made.status();
    runtime_ = *made;
    std::lock_guard<std::mutex> current_lock(runtime_mutex);
    current_runtime = runtime_;
    return runtime_;
  }

  GpuBackendOptions options_;
  std::mutex mutex_;
  std::shared_ptr<GpuRuntime> runtime_;
};

}  // namespace

Status RegisterGpuBackend(const GpuBackendOptions& options) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  engine::SetGpuProvider(std::make_shared<CudaProvider>(options));
  return Status::Ok();
}

bool BuiltWithCuda() { return true; }

std::string DeviceName() { return DeviceUnavailableReason().empty() ? Device().name : ""; }

GpuBatchCounts BatchCounts() {
  std::shared_ptr<GpuRuntime> runtime;
  {
    std::lock_guard<std::mutex> lock(runtime_mutex);
    runtime = current_runtime.lock();
  }
  GpuBatchCounts counts;
  if (!runtime) return counts;
  const BatchQueueStats gcc = runtime->gcc_stats(), filter = runtime->filter_stats();
  counts.gcc_batches = gcc.batches;
  counts.gcc_frames = gcc.jobs;
  counts.filter_batches = filter.batches;
  counts.filter_steps = filter.jobs;
  return counts;
}

}  // namespace localizer::gpu
