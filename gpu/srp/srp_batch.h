// SRP-PHAT for many sessions' frames at once on the GPU: the steered response power of every
// session's pair spectra at every direction of its array's grid (the map, in the CPU's z
// units), the map's arg-max, and the CPU's Newton refinement on the exact spectrum from there.
//
// Inputs, per session frame (SrpJob): its array (one of the arrays given at Create, each with
// its sensors, engine::SrpOptions and direction grid) and its pair spectra: for the P pairs in
// PairSpectra's order, the B in-band PHAT-weighted cross-spectrum values
// G_p(k) = X_i conj(X_j) / |X_i conj(X_j)| (0 where a channel is silent) that
// engine::PairSpectra computes, pair-major, complex float (P x B of them).
// Outputs, per session: the map (optional; z(u) per grid direction, float), the grid's best
// direction and z, and (SrpArrayConfig::refine) the refined direction (or cone angle) and z,
// described as engine::SrpPhat describes a peak (planar arrays: mirror side per source_side).
// Only the strongest source is sought; the CPU's removal of found sources and search for more
// (max_sources > 1) stay on the CPU.
//
// Equality with the CPU (tests/gpu/srp_math_test.cu on the host, srp_batch_test.cc on the
// device): the map equals engine::SrpPhat::Statistic at each grid direction within
// kSrpMapToleranceZ (float sums along re-anchored phasor chains, srp_math.cuh), its arg-max is
// the CPU map's (or ties with it within that tolerance), and the refined peak is the one
// SrpPhat::Analyse reports (direction within kSrpDirectionToleranceRad, z within
// kSrpStatisticToleranceRelative) when the grid is the CPU's (CpuLikeGrid): the refinement is
// the CPU's Newton's method, in double, on the same exact spectrum.
//
// The sequence on the batch's stream: the host copies each job's spectra into pinned staging
// (one host copy, checked finite), one copy of the tasks and one of the spectra to the device,
// the map kernel (a block per session and 256 directions, spectra staged in shared memory), the
// peak kernel (a warp per session: arg-max, refinement), the results (and the maps asked for)
// back in one or two copies, one synchronisation.
//
// Memory per session of capacity: 8 P B bytes of spectra and 4 D of map on the device, the
// same again pinned on the host, plus ~80 bytes of task and result. For 4 microphones,
// frames of 256 at 16 kHz, 100-7000 Hz (M = 320, B = 139, P = 6) and a 2562-direction grid:
// 6.5 KiB + 10 KiB device per session (1000 sessions: 17 MiB, and as much pinned).
// Cost per session frame: the map, D x P x B complex multiply-adds in float (plus one
// sincos per pair, direction and 32 bins): 2562 x 6 x 139 ~ 2.1 M (~13 M float operations;
// the CPU-like grid of that board is 291 directions, 0.24 M); the refinement, 1 + up to 24
// probes of P x B double multiply-adds with derivatives (4.5 probes on average, at most 6, on
// the host test's plane waves: ~4 k).
// The bus carries 8 P B bytes in and 56 bytes out per session (plus 4 D with the map).
//
// Not thread-safe: one thread runs a batch at a time. Run blocks until the results are on the
// host.
#pragma once

#include <complex>
#include <limits>
#include <memory>
#include <span>
#include <vector>

#include "engine/core/status.h"
#include "engine/core/types.h"
#include "engine/doa/srp_phat.h"
#include "gpu/srp/srp_array.h"

namespace localizer::gpu {

// The stated agreement with the CPU (double) on the same spectra, held by the tests (measured
// on the host, tests/gpu/srp_math_test.cu, 2026-12-03, over 32-40 plane-wave frames on eight
// arrays: map 7.5e-6 z with frames of 256 samples, 2.3e-5 z with 1024 and 28 pairs; direction
// 1.6e-8 rad; statistic 1.8e-9 relative).
// The map: |z_gpu - z_cpu| at every grid direction, in z units (a source's peak is tens; the
// noise-only deviation is 1). The float error grows with the bins and pairs summed: 4x the
// largest host measurement leaves room for the device's fused multiply-adds and sincosf.
constexpr double kSrpMapToleranceZ = 1e-4;
// The refined direction (radians; cone angle for linear arrays) against the CPU's Analyse: the
// refinement's own convergence step (kRefineConverged_rad), which a different accept/reject at
// the last halving could move it by.
constexpr double kSrpDirectionToleranceRad = 1e-5;
// The refined statistic z, relative.
constexpr double kSrpStatisticToleranceRelative = 1e-6;

struct SrpArrayConfig {
  std::vector<engine::Vec3> sensors_m;
  // sample_rate_hz, sound_speed_mps, frame_samples, the band and source_side are used (they fix
  // the spectra's layout and the lags); the search options are the CPU's alone.
  engine::SrpOptions options;
  // The grid: unit vectors (normalised here), at least one. CpuLikeGrid (srp_grid.h) gives the
  // CPU's own.
  std::vector<engine::Vec3> directions;
  bool refine = true;
};

// What was found for one session's frame.
struct SrpPeak {
  static constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
  int grid_index = -1;     // the map's first maximum
  double grid_z = kNan;    // z there (float map)
  // Unit vector towards the source (NaN for linear arrays), after the refinement when asked.
  engine::Vec3 direction = engine::Vec3::Constant(kNan);
  double cone_angle_rad = kNan;  // linear arrays
  bool mirror_ambiguous = false;  // planar arrays without source_side (as DirectionPeak)
  engine::Vec3 mirror_direction = engine::Vec3::Constant(kNan);
  double statistic = kNan;  // z at the reported direction (refined: double, the CPU's Exact)
  double threshold = 0.0;   // the CPU's detection threshold for this array
  int iterations = 0;       // Newton iterations (0 without refinement)
};

// One session's frame to evaluate.
struct SrpJob {
  int array = 0;                                // index into Create's arrays
  const std::complex<float>* spectra = nullptr;  // P x B values, pair-major (host memory)
  SrpPeak* out = nullptr;
  std::vector<float>* map_z = nullptr;  // optional: receives z at each grid direction
};


// What Run reports for one kernel result (srp_kernels.h) of an array: SrpPhat::Describe's
// rules (planar arrays: the source_side's side, or the normal's with the mirror as the other
// candidate; linear arrays: the cone angle alone). Public so that the host tests check it.
struct SrpSessionResult;
SrpPeak DescribeSrpResult(const SrpArrayModel& model, const SrpSessionResult& result);

class SrpBatch {
 public:
  // Event timings of the last Run, milliseconds of device time (0 unless created with
  // collect_timing): total from the first copy's start to the last copy's end, kernels the two
  // kernels alone.
  struct Timing {
    float total_ms = 0.0f;
    float kernels_ms = 0.0f;
  };

  // Device buffers, pinned staging and a stream for up to max_sessions jobs a Run.
  // INVALID_ARGUMENT for no array, an array engine::SrpPhat::Create refuses, a grid empty or of
  // more than 2^22 directions, a non-finite direction, max_sessions outside [1, 1 << 20], or a session's spectra beyond the
  // device's shared memory; RESOURCE_EXHAUSTED when memory runs out; FAILED_PRECONDITION
  // without a usable device.
  static StatusOr<std::unique_ptr<SrpBatch>> Create(std::vector<SrpArrayConfig> arrays, int max_sessions,
                                                    bool collect_timing = false);
  ~SrpBatch();
  SrpBatch(const SrpBatch&) = delete;
  SrpBatch& operator=(const SrpBatch&) = delete;

  // Evaluates every job. INVALID_ARGUMENT, before any device work, when jobs is empty or longer
  // than max_sessions, a job names no array or has a null spectra/out pointer, or a spectrum
  // holds a non-finite value ("job j: ..."). A CUDA failure returns its Status (outputs
  // untouched). Allocates only for map_z vectors that must grow.
  Status Run(std::span<const SrpJob> jobs);

  Timing last_timing() const;
  int max_sessions() const;
  int array_count() const;
  const SrpArrayModel& array(int a) const;
  // The normalised grid of array a.
  const std::vector<engine::Vec3>& directions(int a) const;

 private:
  struct Impl;
  explicit SrpBatch(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace localizer::gpu
