// Host side of the particle bank: a session's fixed configuration (geometry relative to the
// array centroid, options turned into the float constants the kernels use), and the
// translation of one step's inputs into the SessionStep descriptor the kernels read,
// including the GCC windows upsampled on the host (engine/filters/gcc_upsampling.h) with the
// gain of engine::GccGain. Plain C++ (g++), no device calls: tested without a GPU
// (tests/gpu/pf_step_builder_test.cc). The constants are rounded to float exactly as
// engine::ParticleSet rounds them, so both filters weigh with the same numbers.
#pragma once

#include <vector>

#include "engine/array/array_geometry.h"
#include "engine/core/measurement.h"
#include "engine/filters/particle_filter.h"
#include "gpu/filters/pf_kernels.h"

namespace localizer::gpu::pf {

struct SessionConfig {
  engine::ParticleFilterOptions options;
  int pairs = 0;
  double origin_m[3] = {};                // array centroid, world frame
  float reference[3] = {};                // reference sensor - centroid
  float pair_sensor[kMaxPairs][3] = {};   // each pair's sensor - centroid
  float inv_c = 0.0f;                     // 1 / sound speed
  double kernel_h = 0.0, kernel_a = 1.0;  // Liu-West bandwidth and shrinkage (kernel_scale > 0)
  // Manoeuvres (options.manoeuvre_share): a particle manoeuvres when its fourth normal is
  // below manoeuvre_z = Phi^-1(share) (-inf: never); its acceleration normals' gains.
  float manoeuvre_z = -1e30f, quiet_gain = 1.0f, manoeuvre_gain = 1.0f;
};

// INVALID_ARGUMENT for options that fail Validate() or an array with more than kMaxPairs
// pairs (16 sensors).
StatusOr<SessionConfig> MakeSessionConfig(const engine::ArrayGeometry& array,
                                          const engine::ParticleFilterOptions& options);

// One step's inputs, as in ParticleBank::StepRequest.
struct StepInputs {
  double dt_s = 0.0;                                 // > 0: predict by this first
  const engine::Measurement* measurement = nullptr;  // nullptr: predict only
  const int* used = nullptr;                         // per pair, 1: use it
  const double* sigmas_s = nullptr;                  // per pair TDOA noise std (s)
};

// Fills every field of `step` but slot, first_block, draw and prior_ess (the bank's); appends
// the fine GCC windows of GCC-likelihood pairs to `gcc` (their offsets into it go in
// step->pair[p].gcc_offset). INVALID_ARGUMENT (naming the field) for a non-finite dt, a
// measurement whose pair count differs from the array's, missing used/sigmas, a used pair
// with a non-finite delay or a sigma not > 0, or a GCC pair without sample_rate_hz > 0.
// step->do_update is 1 only with a measurement and at least one used pair.
Status FillSessionStep(const SessionConfig& config, const StepInputs& in, std::vector<float>* gcc, SessionStep* step);

}  // namespace localizer::gpu::pf
