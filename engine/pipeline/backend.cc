#include "engine/pipeline/backend.h"

#include <mutex>

namespace localizer::engine {
namespace {

std::mutex& ProviderMutex() {
  static std::mutex mutex;
  return mutex;
}
std::shared_ptr<BackendProvider>& ProviderSlot() {
  static std::shared_ptr<BackendProvider> provider;
  return provider;
}
std::shared_ptr<BackendProvider> CurrentProvider() {
  std::lock_guard<std::mutex> lock(ProviderMutex());
  return ProviderSlot();
}

}  // namespace

std::shared_ptr<BackendProvider> SetGpuProvider(std::shared_ptr<BackendProvider> provider) {
  std::lock_guard<std::mutex> lock(ProviderMutex());
  std::swap(ProviderSlot(), provider);
  return provider;
}

std::string GpuUnavailableReason() {
  const auto provider = CurrentProvider();
  if (!provider) return "this program has no GPU backend (built without CUDA, or gpu/ not registered)";
  return provider->UnavailableReason();
}

StatusOr<SessionComponents> BuildComponents(const std::string& backend, const ArrayGeometry& array,
                                            const GccOptions& gcc, const ParticleFilterOptions& filter) {
  if (backend != "cpu" && backend != "gpu" && backend != "auto") {
    return InvalidArgument("backend '" + backend + "' is not one of: auto, cpu, gpu");
  }
  SessionComponents parts;
  if (backend != "cpu") {
    const auto provider = CurrentProvider();
    const std::string reason = provider ? provider->UnavailableReason() : GpuUnavailableReason();
    if (reason.empty()) {
      auto estimator = provider->MakeEstimator(array, gcc);
      if (!estimator.ok()) return estimator.status();
      auto tracker = provider->MakeTracker(array, filter);
      if (!tracker.ok()) return tracker.status();
      parts.estimator = std::move(estimator).value();
      parts.tracker = std::move(tracker).value();
      parts.backend = "gpu";
      return parts;
    }
    if (backend == "gpu") return FailedPrecondition("backend gpu requested but unavailable: " + reason);
  }
  auto estimator = GccPhatEstimator::Create(array, gcc);
  if (!estimator.ok()) return estimator.status();
  auto tracker = ParticleFilter::Create(array, filter);
  if (!tracker.ok()) return tracker.status();
  parts.estimator = std::move(estimator).value();
  parts.tracker = std::move(tracker).value();
  parts.backend = "cpu";
  return parts;
}

}  // namespace localizer::engine
