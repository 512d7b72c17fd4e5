// GccPhatEstimator's state and steps, shared by gcc_phat.cc (transforms, weighting, the main
// peak and MeasurePair) and gcc_peak.cc (the spectrum statistics behind delay_sigma, the
// coherence weights and the candidate peaks). Internal to engine/tdoa; see gcc_phat.h for
// what they compute.
#pragma once

#include <cmath>
#include <numbers>
#include <span>
#include <vector>

#include "engine/tdoa/fftw_util.h"
#include "engine/tdoa/gcc_layout.h"
#include "engine/tdoa/gcc_phat.h"

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
inline double InterpolationErrorSamples(PeakInterpolation method, std::span<const float, kPeakSamples> samples,
                                        double offset) {
  if (method == PeakInterpolation::kSinc) return kSincFloorSamples;
  const double bias = offset - InterpolatePeak(PeakInterpolation::kSinc, samples);
  return std::sqrt(bias * bias + kSincFloorSamples * kSincFloorSamples);
}

struct GccPhatEstimator::Impl {
  Impl(const ArrayGeometry& geometry, const GccOptions& opts) : array(geometry), options(opts) {}

  Status Init();
  Status TransformChannel(const float* samples, int channel);
  float WeighCrossSpectrum(int pair);
  void MeasurePair(int pair, PairMeasurement* out);
  void GatherWindow(int max_lag, float scale);
  float LargestSidelobe(std::span<const float> searched, int peak, int peak_lag, float scale) const;
  struct SpectrumStats {
    double level = 0.0;      // sum c_k Re_k            (S R at the delay)
    double first = 0.0;      // sum c_k w_k Re_k
    double curvature = 0.0;  // sum c_k w_k^2 Re_k      (-S R'' at the delay)
    double slope_var = 0.0;  // sum c_k^2 w_k^2 Im_k^2  (S^2 var R' at the delay, independent bins)
  };
  SpectrumStats AnalyseSpectrum(int pair, double delay_samples);
  void LearnCoherence(int pair);
  void PickCandidates(std::span<const float> searched, int peak, int max_lag, double radius, double slope_std,
                      PairMeasurement* out);
  double SigmaCapSamples(int max_lag) const { return (2.0 * max_lag + 1.0) / std::sqrt(12.0); }

  ArrayGeometry array;
  GccOptions options;
  // N, bins, band, noise floor and L_p per pair (gcc_layout.h).
  GccLayout layout;
  int spectrum_stride = 0;     // floats from one channel's spectrum to the next (64-byte multiple)
  std::vector<double> energy;  // sum of squares per channel, this frame
  std::vector<float> window;   // scaled R at lags -(L + K) .. L + K, K = kPeakHalfWidth
  FftwFloats padded;           // N: one channel, zero padded
  FftwFloats spectra;          // channels * spectrum_stride: interleaved X per channel
  FftwFloats cross;            // 2 * bin_count: weighted cross-spectrum (c2r input)
  FftwFloats corr;             // N: inverse transform output, lag l at index l mod N
  FftwFloats weighed;          // 2 * bin_count: `cross` kept before c2r destroys it
  // kPhatCoherence, per pair (pair * bin_count + bin): the running average of the aligned
  // coherence (not yet bias corrected), the weight w it gives the next frame, the frames
  // averaged, and whether the weights hold anything (else the pair falls back to PHAT).
  std::vector<float> coherence;
  std::vector<float> coherence_weight;
  std::vector<int> coherence_frames;
  std::vector<char> coherence_usable;
  struct Extremum {
    float magnitude;
    int index;
  };
  std::vector<Extremum> extrema;  // scratch for PickCandidates
  FftwPlan forward;
  FftwPlan inverse;
};


}  // namespace localizer::engine
