// GccPhatEstimator's state and steps, shared by gcc_phat.cc (transforms, weighting, the main
// peak and MeasurePair) and gcc_peak.cc (the spectrum statistics behind delay_sigma, the
// coherence weights and the candidate peaks). Internal to engine/tdoa; see gcc_phat.h for
// what they compute.
#pragma once

#include <cmath>
#include <numbers>
#include <span>
#include <vector>

#include "engine/tdoa/delay_statistics.h"
#include "engine/tdoa/fftw_util.h"
#include "engine/tdoa/gcc_layout.h"
#include "engine/tdoa/gcc_phat.h"

namespace localizer::engine {

struct GccPhatEstimator::Impl {
  Impl(const ArrayGeometry& geometry, const GccOptions& opts) : array(geometry), options(opts) {}

  Status Init();
  Status TransformChannel(const float* samples, int channel);
  // After the plain pairs: each pair whose sensor has a delay rate is measured again with
  // that channel read along it (delay_warp.h) and keeps the reading whose peak is higher; the
  // spectra are left as the kept readings'.
  void MeasureWarpedPairs(const float* frame, Measurement* out);
  float WeighCrossSpectrum(int pair);
  float WeighSensors(int ref, int sensor, int pair);
  // S / sqrt(the noise-only variance of S R) for the weights in `weighed`: 1 / (R's noise-only
  // standard deviation), for weights that are not PHAT's unit ones; times the taper's factor (gcc_layout.h).
  float WeighedNoiseFloorInverse(float norm) const;
  void MeasurePair(int pair, PairMeasurement* out);
  // Cross pair `index` of layout.cross_sensors: its GCC over its window and noise scale.
  void MeasureCrossPair(int index, CrossPairGcc* out);
  void GatherWindow(int max_lag, float scale);
  float LargestSidelobe(std::span<const float> searched, int peak, int peak_lag, float scale) const;
  // The moments of the kept cross-spectrum at the measured delay (delay_statistics.h).
  SpectrumMoments AnalyseSpectrum(int pair, double delay_samples);
  void LearnCoherence(int pair);

  ArrayGeometry array;
  GccOptions options;
  // N, bins, band, noise floor and L_p per pair (gcc_layout.h).
  GccLayout layout;
  int spectrum_stride = 0;           // floats from one channel's spectrum to the next (64-byte multiple)
  std::vector<float> taper_gains;    // the frame's taper, TaperGain per sample; empty without one
  std::vector<double> energy;        // sum of squares per channel, this frame
  std::vector<double> sensor_rate;   // SetDelayRates per sensor (the reference's 0); empty: none
  std::vector<float> warped;         // frame_samples: one channel read along its delay rate
  std::vector<float> kept_spectrum;  // spectrum_stride: a channel's plain spectrum while its warped one is tried
  PairMeasurement warped_pair;       // a pair measured with its sensor's channel warped
  std::vector<float> window;         // scaled R at lags -(L + K) .. L + K, K = kPeakHalfWidth
  FftwFloats padded;                 // N: one channel, zero padded
  FftwFloats spectra;                // channels * spectrum_stride: interleaved X per channel
  FftwFloats cross;                  // 2 * bin_count: weighted cross-spectrum (c2r input)
  FftwFloats corr;                   // N: inverse transform output, lag l at index l mod N
  FftwFloats weighed;                // 2 * bin_count: `cross` kept before c2r destroys it
  // kPhatCoherence, per pair (pair * bin_count + bin): the running average of the aligned
  // coherence (not yet bias corrected), the weight w it gives the next frame, the frames
  // averaged, and whether the weights hold anything (else the pair falls back to PHAT).
  std::vector<float> coherence;
  std::vector<float> coherence_weight;
  std::vector<int> coherence_frames;
  std::vector<char> coherence_usable;
  std::vector<WindowExtremum> extrema;  // scratch for PickDelayCandidates
  bool have_spectra = false;            // `spectra` hold the last frame Estimate took (MeasureCrossPairs)
  FftwPlan forward;
  FftwPlan inverse;
};

}  // namespace localizer::engine
