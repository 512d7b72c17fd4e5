// Builds a session's TDOA estimator and tracker for the requested compute backend.
//
//   "cpu"  FFTW3 GCC-PHAT and the CPU particle filter; always available.
//   "gpu"  the CUDA implementations in gpu/, when this build has them and a device is
//          present; otherwise FAILED_PRECONDITION saying why — never a silent fallback.
//   "auto" the GPU when available, else the CPU.
// Only this factory decides between implementations; the session sees the interfaces.
#pragma once

#include <memory>
#include <string>

#include "engine/array/array_geometry.h"
#include "engine/filters/particle_filter.h"
#include "engine/tdoa/gcc_phat.h"

namespace localizer::engine {

struct SessionComponents {
  std::unique_ptr<TdoaEstimator> estimator;
  std::unique_ptr<Tracker> tracker;
  std::string backend;  // what was chosen: "cpu" or "gpu"
};

// INVALID_ARGUMENT for an unknown backend name; FAILED_PRECONDITION for "gpu" without one;
// otherwise whatever the estimator's or filter's options validation says.
StatusOr<SessionComponents> BuildComponents(const std::string& backend, const ArrayGeometry& array,
                                            const GccOptions& gcc, const ParticleFilterOptions& filter);

// Why the GPU backend cannot be used here, or "" when it can.
std::string GpuUnavailableReason();

}  // namespace localizer::engine
