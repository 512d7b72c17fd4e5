#include "engine/pipeline/backend.h"

namespace localizer::engine {

std::string GpuUnavailableReason() {
  // The CUDA backend (gpu/) is not part of this build yet.
  return "this build has no GPU backend (gpu/ is not compiled in)";
}

StatusOr<SessionComponents> BuildComponents(const std::string& backend, const ArrayGeometry& array,
                                            const GccOptions& gcc, const ParticleFilterOptions& filter) {
  if (backend != "cpu" && backend != "gpu" && backend != "auto") {
    return InvalidArgument("backend '" + backend + "' is not one of: auto, cpu, gpu");
  }
  if (backend == "gpu") {
    return FailedPrecondition("backend gpu requested but unavailable: " + GpuUnavailableReason());
  }
  SessionComponents parts;
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
