// What a pair's GCC says about its delay beyond the main peak (gcc_phat.h): the delay's
// standard deviation on this frame (PairMeasurement::delay_sigma_s) from the moments of the
// weighted cross-spectrum aligned at the measured delay, and the candidate peaks. Every front
// end that fills a Measurement goes through these functions, so that the CPU estimator
// (gcc_phat.cc, moments in one pass over the kept cross-spectrum) and the GPU batch
// (gpu/tdoa, moments reduced on the device) give the same sigma and candidates from the same
// numbers: the filters anchor each pair's noise to the sigma (filters/pair_noise.h), and
// multipath association picks among the candidates.
#pragma once

#include <cmath>
#include <numbers>
#include <span>
#include <vector>

#include "engine/core/measurement.h"
#include "engine/tdoa/peak_interpolation.h"

namespace localizer::engine {

inline constexpr int kMaxCandidates = 32;  // GccOptions::max_candidates at most
// The envelope of a flat band of width B (rad/sample) is sinc-like with its first null at
// 2 pi / B = (2 pi / sqrt(12)) / sigma_omega, sigma_omega = B / sqrt(12) its rms width.
inline constexpr double kEnvelopeNullPerRmsWidth = 2.0 * std::numbers::pi / 3.4641016151377544;

// The sinc interpolator's own rms error on a clean frame (peak_interpolation.h: 0.0011 sample
// noiseless, rounded up), added in quadrature to delay_sigma: the statistical part alone
// would claim less than the method delivers on a clean frame.
inline constexpr double kSincFloorSamples = 0.002;

// The refinement's systematic error on this peak: for kParabolic and kGaussian their distance
// from the (nearly unbiased) kSinc refinement of the same samples, which is their bias here
// (0.04-0.06 sample at 11 kHz, far less on a peak many samples wide); kSinc's floor else.
// `sinc_offset` is InterpolatePeak(kSinc, samples) (ignored for kSinc).
inline double InterpolationErrorSamples(PeakInterpolation method, double offset, double sinc_offset) {
  if (method == PeakInterpolation::kSinc) return kSincFloorSamples;
  const double bias = offset - sinc_offset;
  return std::sqrt(bias * bias + kSincFloorSamples * kSincFloorSamples);
}
inline double InterpolationErrorSamples(PeakInterpolation method, std::span<const float, kPeakSamples> samples,
                                        double offset) {
  if (method == PeakInterpolation::kSinc) return kSincFloorSamples;
  return InterpolationErrorSamples(method, offset, InterpolatePeak(PeakInterpolation::kSinc, samples));
}

// The largest sigma a pair can have: a delay uniform over its 2 L + 1 searched lags.
inline double SigmaCapSamples(int max_lag) { return (2.0 * max_lag + 1.0) / std::sqrt(12.0); }

// Moments of the in-band bins of the weighted cross-spectrum G rotated to the measured delay
// d: A_k = G_k exp(j w_k d) = Re_k + j Im_k, w_k = 2 pi k / N (rad/sample), c_k = 2 for the
// bins that stand for a conjugate pair and 1 for DC and Nyquist.
struct SpectrumMoments {
  double level = 0.0;      // sum c_k Re_k            (S R at the delay)
  double first = 0.0;      // sum c_k w_k Re_k
  double curvature = 0.0;  // sum c_k w_k^2 Re_k      (-S R'' at the delay)
  double slope_var = 0.0;  // sum c_k^2 w_k^2 Im_k^2  (S^2 var R' at the delay, independent bins)
};

// From the moments, S (the full spectrum's sum of |G|, R's normaliser), N / frame_samples
// (the zero padding: N / M bins per independent one) and the refinement's floor:
struct DelaySpread {
  double slope_std = 0.0;      // standard deviation of R' at the delay
  double sigma_samples = 0.0;  // the delay's: slope_std / |R''| with the floor, at most the cap
  double radius_lags = 1.0;    // candidates at least this far apart: the envelope's first null
};
DelaySpread SpreadFromMoments(const SpectrumMoments& moments, float norm, double padding_factor, double floor_samples,
                              int max_lag);

// The candidate peaks (PairMeasurement::candidates): local extrema of R in the searched
// window, the main peak first (filled from out's delay_s, peak_value and delay_sigma_s), then
// by decreasing |R|, each at least spread.radius_lags from those taken, refined like the main
// peak (negative ones on -R), up to max_candidates. `searched` holds R at lags -L..L and
// searched.data()[-kPeakHalfWidth .. -1] and [2L + 1 .. 2L + kPeakHalfWidth] must be valid
// (R at the lags beyond). `scratch` is reused between calls (may be null for max_candidates 1).
struct WindowExtremum {
  float magnitude;
  int index;
};
void PickDelayCandidates(std::span<const float> searched, int peak, int max_lag, const DelaySpread& spread,
                         PeakInterpolation interpolation, double sample_rate_hz, int max_candidates,
                         std::vector<WindowExtremum>* scratch, PairMeasurement* out);

}  // namespace localizer::engine
