// Builds a session's TDOA estimator and tracker for the requested compute backend.
//
//   "cpu"  FFTW3 GCC-PHAT and the CPU trackers; always available.
//   "gpu"  the implementations a registered GPU provider makes (gpu/ registers the CUDA
//          one at start-up: gpu/backend/gpu_backend.h), when a provider is registered and
//          says it is usable; otherwise FAILED_PRECONDITION saying why — never a silent
//          fallback.
//   "auto" the GPU when available, else the CPU.
// Only this factory decides between implementations; the session sees the interfaces.
// The engine knows no GPU code: the provider is an interface that a library linked into
// the program (server, CLI, tests) hands in.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "engine/array/array_geometry.h"
#include "engine/filters/imm_filter.h"
#include "engine/filters/kalman_filter.h"
#include "engine/filters/multi_model_pf.h"
#include "engine/filters/particle_filter.h"
#include "engine/tdoa/gcc_phat.h"

namespace localizer::engine {

struct SessionComponents {
  std::unique_ptr<TdoaEstimator> estimator;
  std::unique_ptr<Tracker> tracker;
  std::string backend;  // what was chosen: "cpu" or "gpu"
};

// A compute backend other than the CPU's. Implementations must be thread-safe: sessions
// are created on many threads.
class BackendProvider {
 public:
  virtual ~BackendProvider() = default;
  // Why this backend cannot be used here (no device, driver too old, ...), or "" when it can.
  virtual std::string UnavailableReason() const = 0;
  // Same contracts as GccPhatEstimator::Create / ParticleFilter::Create; errors of the
  // device (memory exhausted, ...) come back as Status, never as a crash.
  virtual StatusOr<std::unique_ptr<TdoaEstimator>> MakeEstimator(const ArrayGeometry& array,
                                                                 const GccOptions& options) = 0;
  virtual StatusOr<std::unique_ptr<Tracker>> MakeTracker(const ArrayGeometry& array,
                                                         const ParticleFilterOptions& options) = 0;
};

// Installs the provider "gpu" and "auto" consult (nullptr removes it). Process-wide; call
// before sessions are created. Returns the provider it replaced.
std::shared_ptr<BackendProvider> SetGpuProvider(std::shared_ptr<BackendProvider> provider);

// Which tracker a session runs. The particle filter runs on the chosen backend (with the
// mixture likelihood, on the CPU); the Kalman
// filters (microseconds per update), the IMM and the multiple-model particle filter always
// run on the CPU, beside a GPU GCC when "gpu" (the GPU provider makes only the plain PF).
struct TrackerOptions {
  std::string type = "pf";          // "pf" | "ekf" | "ukf" | "mmpf" | "imm"
  ParticleFilterOptions particle;   // "pf"; "mmpf": particles, likelihood, noise, seed
  std::vector<ParticleMotion> mmpf_models;  // "mmpf": its hypotheses; empty: the defaults
                                            // (multi_model_pf.h) for particle.accel_noise_mps2
  KalmanOptions kalman;             // "ekf", "ukf" (the variant follows the type); "imm":
                                    // the modes' shared options, variant included
  std::vector<ImmMode> imm_modes = ImmOptions().modes;  // "imm": cv + ct by default
  double stay_probability = 0.95;   // "mmpf", "imm": the Markov switching prior per step
  // The array moves (a platform's attitude, Tracker::SetArray every frame). The GPU filter
  // keeps its sensors on the device, so such a particle filter runs on the CPU beside the
  // GPU GCC (the GCC's lag window depends only on sensor distances, which do not change).
  bool moving_array = false;
};

// INVALID_ARGUMENT for an unknown backend name; FAILED_PRECONDITION for "gpu" without one;
// otherwise whatever the estimator's or filter's options validation (or the provider) says.
StatusOr<SessionComponents> BuildComponents(const std::string& backend, const ArrayGeometry& array,
                                            const GccOptions& gcc, const TrackerOptions& tracker);

// Why the GPU backend cannot be used here, or "" when it can.
std::string GpuUnavailableReason();

}  // namespace localizer::engine
