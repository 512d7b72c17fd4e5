// The shape of one session's GCC-PHAT transforms, computed from its array and options: the
// pure arithmetic that every implementation of the stage (GccPhatEstimator on FFTW, the
// batched cuFFT stage in gpu/tdoa) must agree on, kept in one place so they cannot drift.
//
// For an array with pairs p = 0..P-1 (ArrayGeometry's order) and options o:
//   L_p   = min(ceil(max_delay_s(p) * fs) + o.lag_margin_samples, N/2 - 1 - K)   [samples]
//           the half-width of pair p's searched lag window (K = kPeakHalfWidth)
//   N     = NextFastFftSize(frame_samples + min(max_p wanted_p, frame_samples) + K + 1)
//           with wanted_p the unclamped L_p: the smallest 2^a, 3 * 2^a or 5 * 2^a long
//           enough that the circular correlation equals the linear one at every lag the
//           stage reads (see gcc_phat.h)
//   bins  = N/2 + 1 (the half spectrum of a real transform)
//   band  = bins [ceil(band_low_hz N / fs), floor(band_high_hz N / fs) + 1), clipped to
//           bins (band_high_hz = 0: up to Nyquist)
//   noise_floor_inverse = sqrt(2 * in-band bins / G): 1 / (noise-only std of R), measurement.h,
//           where G = n sum w^4 / (sum w^2)^2 over the frame's taper w (n = frame_samples;
//           1 for a rectangle, 1.12 for the default Tukey 0.2, 1.94 for Hann): a taper
//           correlates neighbouring bins, which widens R's noise-only spread by sqrt(G)
//           (gcc_detection_test measures 1.04, 1.13 and 1.35 against 1.06, 1.16 and 1.39)
//   window_time_var_s2 = sum w^2 t^2 / sum w^2 over the frame's samples, t from its centre
//           (Measurement::window_time_var_s2: T^2 / 12 for a rectangle, 0.0200 T^2 for Hann)
// Cost: O(pairs). Thread-safe (a pure function).
#pragma once

#include <array>
#include <vector>

#include "engine/array/array_geometry.h"
#include "engine/core/status.h"
#include "engine/tdoa/gcc_phat.h"

namespace localizer::engine {

struct GccLayout {
  int frame_samples = 0;             // samples per channel per frame (options.frame_samples)
  int channels = 0;                  // the array's sensor count
  int fft_size = 0;                  // N, samples
  int bin_count = 0;                 // N/2 + 1
  int band_first_bin = 0;            // bins [band_first_bin, band_end_bin) are in the band;
  int band_end_bin = 0;              // band_first_bin < band_end_bin <= bin_count
  float noise_floor_inverse = 0.0f;  // sqrt(2 * (band_end_bin - band_first_bin)) * taper_noise_factor
  float taper_noise_factor = 1.0f;   // 1 / sqrt(G), G as above: applies to any bin weighting
  double window_time_var_s2 = 0.0;   // as above, s^2
  std::vector<int> max_lag_samples;  // L_p per pair, in [0, N/2 - 1 - kPeakHalfWidth]
  // Pairs of non-reference sensors measured for redundancy (GccOptions::cross_pairs_max_sensors;
  // empty unless the array has at most that many sensors and the GCC is kept): sensors
  // (a, b), a < b, ascending, and each one's half-width, min(wanted, N/2 - 1 - K,
  // N - frame_samples - K - 1): beyond the last the circular correlation aliases.
  std::vector<std::array<int, 2>> cross_sensors;
  std::vector<int> cross_max_lag_samples;

  int pair_count() const { return static_cast<int>(max_lag_samples.size()); }
  int widest_lag() const;  // max L over the pairs and the cross pairs (0 without pairs)
};

// INVALID_ARGUMENT when options.Validate() fails (its message) or the band holds no FFT bin
// ("band [lo, hi] Hz holds no FFT bin (bin spacing ... Hz)").
StatusOr<GccLayout> ComputeGccLayout(const ArrayGeometry& array, const GccOptions& options);

// The frame's taper as n gains (gcc_math.h's TaperGain), empty when taper_fraction leaves no
// sample tapered (a rectangle): the CPU estimator's table and the source of G above.
std::vector<float> TaperGains(int n, double taper_fraction);

}  // namespace localizer::engine
