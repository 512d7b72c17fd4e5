// Device-resident particle filters of many sessions, stepped together.
//
// Each session holds a slot: its particles (float32 structure-of-arrays relative to the
// array centroid, two state buffers), weights and scratch stay in device memory between
// frames. One Step advances any set of sessions in one launch sequence on the bank's stream
// (gpu/filters/pf_kernels.h lists the kernels): per session it does what
// engine::ParticleFilter does per Predict + Update (engine/filters/particle_filter.h holds the
// equations), i.e.
//   predict  p <- p + v dt + a dt^2/2, v <- v + a dt, a ~ N(0, accel_noise^2 I3), scaled by
//            manoeuvre_scale for a manoeuvre_share of the particles (drawn each step)
//   weigh    log w += sum over used pairs of the Student-t (peak) or gain * Catmull-Rom(GCC
//            upsampled 8x) log-likelihood of the predicted delay
//            h' = (r_k - r_ref)/c - (d/2)(vr_k - vr_ref)/c;
//            innovation moments per pair under the prior weights
//   normalise (log-sum-exp), ESS = 1 / sum w^2
//   resample when ESS < resample_threshold * N: systematic (one offset, N pointers; each
//            output finds its parent by binary search of the prefix sums), then the Liu-West
//            move x' = a x + (1 - a) mean + h L z with L the Cholesky root of the weighted
//            covariance and z ~ N(0, I6).
// Differences from the CPU filter, none meant to change its statistics: Philox normals
// (curand) instead of the CPU's counter hash, so runs differ draw by draw, and the kernel
// draws are Gaussian, not triangular (same variance); sums in float per block of 256
// particles and in double per session (the CPU sums in float over all N); the covariance
// root falls back to a zero-pivot Cholesky, not an eigen root, when the covariance is
// singular; exp and log are CUDA's, not engine/core/fast_math.h. On the host model of this
// sequence (tests/gpu/pf_host_model_test.cc) the pooled RMSE is within 1 % of the CPU's.
//
// Replay: random numbers are keyed by (options.seed, particle index, the session's draw
// counter), and every reduction runs over one session's blocks in a fixed order, so a
// session's results are bit-identical run to run and whatever other sessions share its
// Step (no float atomics).
//
// Memory per slot: ~64 bytes per particle plus ~1 byte per particle of per-block partials
// (SlotLayout::For(n).bytes exactly), counted against memory_limit_bytes. The bank also
// keeps staging buffers for Step (descriptors, GCC windows, results; grown on demand, not
// counted in the limit): ~1 KB per request plus the fine GCC windows (4 bytes x 8 x lags
// per pair with the GCC likelihood).
//
// Cost of a Step: one H2D copy of the descriptors and GCC windows, five kernels (about 96
// bytes of device memory traffic per particle without resampling, see
// tests/bench/gpu_pf_bench.cc), one D2H copy of the results, one stream synchronisation.
//
// Thread-safety: every method may be called from any thread; one mutex serialises them, so a
// Step blocks Open/Close/Moments of other threads for its duration.
#pragma once

#include <cstddef>
#include <memory>
#include <span>
#include <vector>

#include "engine/array/array_geometry.h"
#include "engine/core/measurement.h"
#include "engine/core/status.h"
#include "engine/core/types.h"
#include "engine/filters/pair_noise.h"
#include "engine/filters/particle_filter.h"
#include "engine/filters/tracker.h"

namespace localizer::gpu {

class ParticleBank {
 public:
  // memory_limit_bytes: the most device memory all slots together may hold (state
  // double-buffered, weights, scratch); 0 = no limit of our own (the device's memory is).
  // FAILED_PRECONDITION without a usable device; errors of stream creation as Status.
  static StatusOr<std::unique_ptr<ParticleBank>> Create(std::size_t memory_limit_bytes);
  ~ParticleBank();
  ParticleBank(const ParticleBank&) = delete;
  ParticleBank& operator=(const ParticleBank&) = delete;

  // Reserves device memory for a session (options.particles particles) and returns its slot.
  // INVALID_ARGUMENT: options fail Validate(), or the array has more than 16 sensors.
  // RESOURCE_EXHAUSTED (naming the bytes wanted and left) when the limit or the device's
  // memory would be passed; other slots are unaffected. The slot is not initialised.
  StatusOr<int> Open(const engine::ArrayGeometry& array, const engine::ParticleFilterOptions& options);
  // Frees the slot's device memory (no-op for a slot that is not open). The number may be
  // reused by a later Open.
  void Close(int slot);

  // x = mean + root z, z ~ N(0, I6); weights equal (root: e.g. the covariance's square root,
  // as engine::ParticleFilter::Initialise computes it). INVALID_ARGUMENT for a slot not open
  // or a non-finite mean/root.
  Status InitialiseGaussian(int slot, const engine::Vec6& mean, const engine::Mat6& root);
  // Position uniform in [min_m, max_m], velocity ~ N(0, speed_sigma_mps^2 I3); weights equal.
  Status InitialiseRegion(int slot, const engine::Vec3& min_m, const engine::Vec3& max_m, double speed_sigma_mps);

  // Batched (re)initialisation: every request's slot is initialised in ONE launch (one
  // kernel over all their particles, pf_kernels.h LaunchInitialiseBatch) and its moments
  // come back from one predict-only Step over all of them: two launch sequences and one
  // synchronisation for any number of sessions, instead of a launch and a wait for each
  // (what a burst of session starts did). Each slot gets exactly what InitialiseGaussian /
  // InitialiseRegion followed by Moments give it alone (same Philox window, same
  // per-particle maths). results.size() must equal requests.size() (else INVALID_ARGUMENT,
  // nothing runs). A request with a slot not open, a slot already named by an earlier
  // request, or bad values (the one-slot calls' messages) gets that status and is left out;
  // the others run. A CUDA error is returned and set in the result of every request that ran
  // (their slots' particles are then undefined: re-initialise or close them).
  struct InitRequest {
    int slot = -1;
    bool region = false;  // false: Gaussian (mean, root); true: region (min_m, max_m, speed)
    engine::Vec6 mean = engine::Vec6::Zero();
    engine::Mat6 root = engine::Mat6::Zero();
    engine::Vec3 min_m = engine::Vec3::Zero();
    engine::Vec3 max_m = engine::Vec3::Zero();
    double speed_sigma_mps = 0.0;
  };
  struct InitResult {
    Status status;
    engine::TrackState state;  // the slot's weighted moments after initialisation (as Moments)
  };
  Status Initialise(std::span<const InitRequest> requests, std::span<InitResult> results);

  struct StepRequest {
    int slot = -1;
    double dt_s = 0.0;                                 // predict by this first (<= 0: no predict)
    const engine::Measurement* measurement = nullptr;  // nullptr or no used pair: predict only
                                                       // (no weighing/normalising/resampling)
    const int* used = nullptr;                         // per pair: 1 to use it
    const double* sigmas_s = nullptr;                  // per pair: TDOA noise std (s)
  };
  struct StepResult {
    Status status;
    engine::TrackState state;  // weighted mean/cov after the step (absolute coordinates, like
                               // ParticleSet::MeanAndCovariance; after resampling the
                               // moments of the weighted particles before it, as the CPU)
    double ess = 0;            // after normalisation (unchanged on predict-only)
    bool resampled = false;
    bool cholesky_fallback = false;                      // resampled with a singular covariance (see pf_math.cuh)
    std::vector<engine::InnovationMoments> innovations;  // per pair (zeros for unused pairs),
                                                         // as ParticleSet::Weigh reports
  };
  // Steps all requests in ONE launch sequence on the bank's stream and waits for it.
  // results.size() must equal requests.size() (else INVALID_ARGUMENT, nothing runs).
  // A request that is invalid (slot not open or not initialised: FAILED_PRECONDITION /
  // INVALID_ARGUMENT; a slot already named by an earlier request; bad inputs, see
  // pf::FillSessionStep) gets that status in its result and is left out; the others run.
  // A CUDA error is returned and also set in the result of every request that ran (their
  // slots' particles are then undefined: close them).
  Status Step(std::span<const StepRequest> requests, std::span<StepResult> results);

  // The slot's current weighted mean and covariance (absolute coordinates). Draws nothing.
  StatusOr<engine::TrackState> Moments(int slot);

  std::size_t bytes_in_use() const;        // device bytes held by open slots
  std::size_t memory_limit_bytes() const;  // as given to Create (0: none)
  int open_slots() const;

 private:
  struct Impl;
  explicit ParticleBank(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace localizer::gpu
