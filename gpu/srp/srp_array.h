// One array as the batched SRP-PHAT sees it (srp_batch.h), derived from the CPU analyser's own
// construction (engine::SrpPhat::Create on the same sensors and options), so that the pairs,
// the band's bins, the transform size, the noise deviation and the lags per direction are the
// CPU's: sessions of the GPU batch and the engine's direction sessions read the same spectra.
//
//   D_p = -(m_i - m_j) fs / c             lag of pair p = (i, j) per unit of direction (samples)
//   z(u) = power(u) z_per_power,          z_per_power = 1 / (B sigma sqrt(P))
// with power(u) as srp_math.cuh defines it and sigma = PairSpectra::noise_sigma().
#pragma once

#include <vector>

#include "engine/core/status.h"
#include "engine/core/types.h"
#include "engine/doa/array_shape.h"
#include "engine/doa/srp_phat.h"
#include "gpu/srp/srp_math.cuh"

namespace localizer::gpu {

struct SrpArrayModel {
  engine::ArrayShapeInfo shape;
  int sensors = 0;
  int pairs = 0;        // P = sensors (sensors - 1) / 2, in PairSpectra's order
  int fft_size = 0;     // M
  srp::SrpBand band;    // the in-band bins (consecutive)
  std::vector<double> lag_per_direction;  // D_p, 3 doubles per pair
  double max_spread = 0.0;                // max_p |D_p| (|D_p . axis| for linear arrays)
  double noise_sigma = 0.0;               // PairSpectra::noise_sigma()
  double threshold = 0.0;                 // SrpPhat::threshold(): the z a source must reach
  double z_per_power = 0.0;
  engine::Vec3 source_side = engine::Vec3::Zero();  // SrpOptions::source_side (planar arrays)

  // Floats of one session's spectra: P x B complex values, pair-major.
  int spectrum_floats() const { return 2 * pairs * band.bins; }
  // The refinement's description; points into lag_per_direction (valid while this lives).
  srp::RefineGeometry Geometry() const;
};

// INVALID_ARGUMENT as engine::SrpPhat::Create gives it (options, sensors).
StatusOr<SrpArrayModel> MakeSrpArrayModel(const std::vector<engine::Vec3>& sensors_m, const engine::SrpOptions& options);

}  // namespace localizer::gpu
