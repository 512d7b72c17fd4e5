// Builds a session's TDOA estimator and tracker for the requested compute backend.
//
//   kCpu   FFTW3 GCC-PHAT and the CPU trackers; always available.
//   kGpu   the implementations a registered GPU provider makes (gpu/ registers the CUDA
//          one at start-up: gpu/backend/gpu_backend.h), when a provider is registered and
//          says it is usable; otherwise FAILED_PRECONDITION saying why — never a silent
//          fallback.
//   kAuto  the GPU when available, else the CPU.
// Only this factory decides between implementations; the session sees the interfaces.
// The engine knows no GPU code: the provider is an interface that a library linked into
// the program (server, CLI, tests) hands in.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "engine/array/array_geometry.h"
#include "engine/filters/filter_kind.h"
#include "engine/filters/imm_filter.h"
#include "engine/filters/kalman_filter.h"
#include "engine/filters/multi_model_pf.h"
#include "engine/filters/particle_filter.h"
#include "engine/tdoa/gcc_phat.h"

namespace localizer::engine {

// Names on the wire and in flags: cpu, gpu, auto.
enum class BackendChoice { kCpu, kGpu, kAuto };
// INVALID_ARGUMENT "<field> 'x' is not one of: auto, cpu, gpu".
StatusOr<BackendChoice> ParseBackendChoice(const std::string& name, const std::string& field);
const char* BackendChoiceName(BackendChoice choice);

struct SessionComponents {
  std::unique_ptr<TdoaEstimator> estimator;
  std::unique_ptr<Tracker> tracker;
  std::string backend;  // what was chosen, for reporting: "cpu" or "gpu"
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

// A provider that never builds anything: each Make* fails with FAILED_PRECONDITION naming
// UnavailableReason(), which the subclass says (a build without CUDA, a CLI that hands GPU
// sessions to another executable).
class UnavailableBackendProvider : public BackendProvider {
 public:
  StatusOr<std::unique_ptr<TdoaEstimator>> MakeEstimator(const ArrayGeometry&, const GccOptions&) final {
    return FailedPrecondition(UnavailableReason());
  }
  StatusOr<std::unique_ptr<Tracker>> MakeTracker(const ArrayGeometry&, const ParticleFilterOptions&) final {
    return FailedPrecondition(UnavailableReason());
  }
};

// Installs the provider "gpu" and "auto" consult (nullptr removes it). Process-wide; call
// before sessions are created. Returns the provider it replaced.
std::shared_ptr<BackendProvider> SetGpuProvider(std::shared_ptr<BackendProvider> provider);

// Which tracker a session runs, and the options of each filter it can build. Every filter
// reads only its own options: `particle` (pf, mmpf), `kalman` (ekf, ukf, and each imm
// mode), the imm_* fields (imm). Where the wire and the CLI give one value for all of
// them (accel_noise_mps2, tdoa_sigma_s, min_peak_snr), they write it to both `particle`
// and `kalman`.
// The particle filter runs on the chosen backend (with the mixture likelihood, or on a
// moving array, on the CPU); the Kalman filters (microseconds per update), the IMM and the
// multiple-model particle filter always run on the CPU, beside a GPU GCC when the backend
// is the GPU (the GPU provider makes only the plain PF).
struct TrackerOptions {
  FilterKind kind = FilterKind::kPf;
  // pf, mmpf: particles, likelihood, motion noise (accel_noise_mps2; mmpf: the base of its
  // hypotheses' noise), TDOA noise, pair selection, resampling. Its seed is not read: the
  // session's seed replaces it.
  ParticleFilterOptions particle;
  std::vector<ParticleMotion> mmpf_models;  // mmpf: its hypotheses; empty: the defaults
                                            // (multi_model_pf.h) for particle.accel_noise_mps2
  // ekf, ukf: the filter's options, motion_model and its noise included (only ekf and ukf
  // take a motion model other than cv); imm: the options its modes share. Not read from
  // it: the variant (ekf and ukf are their own; imm's is imm_variant) and, for imm, the
  // motion model (each mode's, from imm_modes).
  KalmanOptions kalman;
  // imm: its modes' motion models (unique, 1 to 8), each with kalman.motion's noise, and
  // its mode filters' variant.
  std::vector<MotionModelKind> imm_modes = {MotionModelKind::kCv, MotionModelKind::kCt};
  KalmanVariant imm_variant = KalmanVariant::kExtended;
  double stay_probability = 0.95;  // mmpf, imm: the Markov switching prior per step
};

// FAILED_PRECONDITION for kGpu without a usable GPU; otherwise whatever the estimator's or
// filter's options validation (or the provider) says. `moving_array`: the array moves
// (a platform's attitude, Tracker::SetArray every frame); the GPU filter keeps its sensors
// on the device, so such a particle filter runs on the CPU beside the GPU GCC (the GCC's lag
// window depends only on sensor distances, which do not change).
StatusOr<SessionComponents> BuildComponents(BackendChoice backend, const ArrayGeometry& array, const GccOptions& gcc,
                                            const TrackerOptions& tracker, bool moving_array);

// Why the GPU backend cannot be used here, or "" when it can.
std::string GpuUnavailableReason();

}  // namespace localizer::engine
