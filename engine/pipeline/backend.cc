#include "engine/pipeline/backend.h"

#include <mutex>
#include <string>

#include "engine/core/enum_names.h"
#include "engine/filters/handoff_tracker.h"

namespace localizer::engine {
namespace {

constexpr EnumName<BackendChoice> kBackendChoices[] = {
    {BackendChoice::kAuto, "auto"}, {BackendChoice::kCpu, "cpu"}, {BackendChoice::kGpu, "gpu"}};

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

// A concrete filter's Create result as a Tracker.
template <typename Filter>
StatusOr<std::unique_ptr<Tracker>> AsTracker(StatusOr<std::unique_ptr<Filter>> made) {
  if (!made.ok()) return made.status();
  return std::unique_ptr<Tracker>(std::move(made).value());
}

// The Kalman filters, whatever the backend.
StatusOr<std::unique_ptr<Tracker>> MakeKalman(const ArrayGeometry& array, const TrackerOptions& tracker) {
  KalmanOptions options = tracker.kalman;
  options.variant = tracker.kind == FilterKind::kUkf ? KalmanVariant::kUnscented : KalmanVariant::kExtended;
  return AsTracker(KalmanFilter::Create(array, options));
}

StatusOr<std::unique_ptr<Tracker>> MakeMultiModelParticleFilter(const ArrayGeometry& array,
                                                                const TrackerOptions& tracker) {
  MultiModelPfOptions options;
  options.particle = tracker.particle;
  options.models = tracker.mmpf_models;
  options.stay_probability = tracker.stay_probability;
  return AsTracker(MultiModelParticleFilter::Create(array, options));
}

StatusOr<std::unique_ptr<Tracker>> MakeImm(const ArrayGeometry& array, const TrackerOptions& tracker) {
  ImmOptions options;
  options.kalman = tracker.kalman;
  options.kalman.variant = tracker.imm_variant;
  options.modes.clear();
  for (MotionModelKind mode : tracker.imm_modes) {
    options.modes.push_back({MotionModelKindName(mode), mode, tracker.kalman.motion});
  }
  options.stay_probability = tracker.stay_probability;
  return AsTracker(ImmFilter::Create(array, options));
}

// Every tracker but the plain particle filter: CPU whatever the backend.
StatusOr<std::unique_ptr<Tracker>> MakeCpuOnly(const ArrayGeometry& array, const TrackerOptions& tracker) {
  switch (tracker.kind) {
    case FilterKind::kMmpf:
      return MakeMultiModelParticleFilter(array, tracker);
    case FilterKind::kImm:
      return MakeImm(array, tracker);
    case FilterKind::kEkf:
    case FilterKind::kUkf:
    case FilterKind::kPf:
      break;
  }
  return MakeKalman(array, tracker);
}

StatusOr<std::unique_ptr<Tracker>> MakeCpuParticleFilter(const ArrayGeometry& array,
                                                         const ParticleFilterOptions& options) {
  return AsTracker(ParticleFilter::Create(array, options));
}

}  // namespace

std::shared_ptr<BackendProvider> SetGpuProvider(std::shared_ptr<BackendProvider> provider) {
  std::lock_guard<std::mutex> lock(ProviderMutex());
  std::swap(ProviderSlot(), provider);
  return provider;
}

StatusOr<BackendChoice> ParseBackendChoice(const std::string& name, const std::string& field) {
  return ParseEnumName(name, field, kBackendChoices);
}

const char* BackendChoiceName(BackendChoice choice) { return EnumNameOf(choice, kBackendChoices); }

std::string GpuUnavailableReason() {
  const auto provider = CurrentProvider();
  if (!provider) return "this program has no GPU backend (built without CUDA, or gpu/ not registered)";
  return provider->UnavailableReason();
}

namespace {
// The device filter holds one hypothesis and no bounds: the CPU filter acquires (every mode
// acquisition finds, the bounds) and hands the track over once one hypothesis is left
// (filters/handoff_tracker.h).
StatusOr<std::unique_ptr<Tracker>> MakeHandoff(const ArrayGeometry& array, const ParticleFilterOptions& options,
                                               BackendProvider& provider) {
  auto device = provider.MakeTracker(array, options);
  if (!device.ok()) return device.status();
  auto cpu = MakeCpuParticleFilter(array, options);
  if (!cpu.ok()) return cpu.status();
  return std::unique_ptr<Tracker>(std::make_unique<HandoffTracker>(std::move(cpu).value(), std::move(device).value()));
}
}  // namespace

StatusOr<SessionComponents> BuildComponents(BackendChoice backend, const ArrayGeometry& array, const GccOptions& gcc,
                                            const TrackerOptions& tracker, bool moving_array) {
  const bool particle = tracker.kind == FilterKind::kPf;
  SessionComponents parts;
  // The learnt coherence weighting keeps per-pair state across frames, and the share
  // weighting reads every channel's spectrum before weighing a pair; the device GCC does
  // neither yet: such sessions run on the CPU (auto) or are refused (gpu).
  const bool cpu_weighting = gcc.weighting == Weighting::kPhatCoherence || gcc.weighting == Weighting::kPhatShare;
  if (backend == BackendChoice::kGpu && cpu_weighting) {
    return FailedPrecondition(std::string("weighting ") + WeightingName(gcc.weighting) +
                              " runs on the CPU backend only (backend cpu or auto)");
  }
  if (backend != BackendChoice::kCpu && !cpu_weighting) {
    const auto provider = CurrentProvider();
    const std::string reason = provider ? provider->UnavailableReason() : GpuUnavailableReason();
    if (reason.empty()) {
      auto estimator = provider->MakeEstimator(array, gcc);
      if (!estimator.ok()) return estimator.status();
      // The device kernels weigh by the peak or GCC likelihood of a fixed array with one
      // acceleration std and no turn rates; the mixture likelihood's particle filter, one
      // with acceleration levels or turn rates and one on a moving array run on the CPU
      // beside the GPU GCC, as the Kalman filters do.
      const bool on_device = particle && tracker.particle.likelihood != Likelihood::kMixture &&
                             tracker.particle.single_motion() && !moving_array;
      auto made = on_device  ? MakeHandoff(array, tracker.particle, *provider)
                  : particle ? MakeCpuParticleFilter(array, tracker.particle)
                             : MakeCpuOnly(array, tracker);
      if (!made.ok()) return made.status();
      parts.estimator = std::move(estimator).value();
      parts.tracker = std::move(made).value();
      parts.backend = "gpu";
      return parts;
    }
    if (backend == BackendChoice::kGpu) return FailedPrecondition("backend gpu requested but unavailable: " + reason);
  }
  auto estimator = GccPhatEstimator::Create(array, gcc);
  if (!estimator.ok()) return estimator.status();
  auto made = particle ? MakeCpuParticleFilter(array, tracker.particle) : MakeCpuOnly(array, tracker);
  if (!made.ok()) return made.status();
  parts.estimator = std::move(estimator).value();
  parts.tracker = std::move(made).value();
  parts.backend = "cpu";
  return parts;
}

}  // namespace localizer::engine
