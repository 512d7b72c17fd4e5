// GccPhatEstimator's state and steps, shared by gcc_phat.cc (transforms, the main peak and
// MeasurePair), gcc_weighing.cc (the weighted cross-spectra and their noise scale) and
// gcc_peak.cc (the spectrum statistics behind delay_sigma, the coherence weights and the
// candidate peaks). Internal to engine/tdoa; see gcc_phat.h for
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
#include "engine/tdoa/packed_transforms.h"
#include "engine/tdoa/signal_share.h"

namespace localizer::engine {

struct GccPhatEstimator::Impl {
  Impl(const ArrayGeometry& geometry, const GccOptions& opts) : array(geometry), options(opts) {}

  Status Init();
  float* SpectrumOf(int channel);  // interleaved X of `channel`; slot sensor_count() is scratch
  // Channels a and b (b < 0: a alone, samples_b unused) through one packed forward transform.
  Status TransformChannels(const float* samples_a, int a, const float* samples_b, int b);
  // After the plain pairs: each pair whose sensor has a delay rate is measured again with
  // that channel read along it (delay_warp.h) and keeps the reading whose peak is higher; the
  // spectra are left as the kept readings'.
  void MeasureWarpedPairs(const float* frame, Measurement* out);
  float WeighCrossSpectrum(int pair, float* g);
  float WeighSensors(int ref, int sensor, int pair, float* g);
  // S / sqrt(the noise-only variance of S R) for the weights in g: 1 / (R's noise-only
  // standard deviation), for weights that are not PHAT's unit ones; times the taper's factor (gcc_layout.h).
  float WeighedNoiseFloorInverse(float norm, const float* g) const;
  // Items [first, end) into out: item i is reference pair i (< pair_count, into out->pairs)
  // or cross pair i - pair_count (into out->cross_pairs, sized by the caller); two items'
  // inverse transforms are packed into one.
  void MeasureItems(int first, int end, Measurement* out);
  float WeighItem(int item, float* g);
  void ReadItem(int item, float norm, const float* g, const float* corr, Measurement* out);
  void MeasureOnePair(int pair, PairMeasurement* out);
  // One pair from its cross-spectrum g (sum of |G| `norm` > 0) and correlation corr (lag l at
  // corr[2 (l mod N)]).
  void ReadPair(int pair, float norm, const float* g, const float* corr, PairMeasurement* out);
  void MeasureWithoutEnergy(int pair, PairMeasurement* out) const;
  // Cross pair `index` of layout.cross_sensors: its GCC over its window and noise scale
  // (norm 0: no energy in the band); g its weighted cross-spectrum.
  void ReadCrossPair(int index, float norm, const float* g, const float* corr, CrossPairGcc* out);
  void GatherWindow(const float* corr, int max_lag, float scale);
  float LargestSidelobe(const float* corr, std::span<const float> searched, int peak, int peak_lag, float scale) const;
  // The moments of the pair's cross-spectrum g at the measured delay (delay_statistics.h).
  SpectrumMoments AnalyseSpectrum(int pair, double delay_samples, const float* g);
  void LearnCoherence(int pair);
  // kPhatShare: this frame's shares of signal from every channel's in-band power, into
  // share_weight (share_flat when the frame has none to give: weighed as PHAT).
  void FindShares();
  // Whether this frame's pairs are weighed by weights other than PHAT's unit ones (learnt
  // coherence for `pair`, or this frame's shares), so R's noise scale is the weights' own.
  bool WeighedBeyondPhat(int pair) const;

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
  FftwFloats spectra;                // (channels + 1) * spectrum_stride: interleaved X per channel (band bins)
  FftwFloats cross;                  // 2 * bin_count: one pair's weighted cross-spectrum (0 out of band)
  FftwFloats cross_b;                // 2 * bin_count: the pair inverted with it (0 out of band)
  // kPhatCoherence, per pair (pair * bin_count + bin): the running average of the aligned
  // coherence (not yet bias corrected), the weight w it gives the next frame, the frames
  // averaged, and whether the weights hold anything (else the pair falls back to PHAT).
  std::vector<float> coherence;
  std::vector<float> coherence_weight;
  std::vector<int> coherence_frames;
  std::vector<char> coherence_usable;
  // kPhatShare: the frame's power per bin (every bin, the band's floor read beside it) summed
  // over the channels, the shares found from it, and the weight of each bin (indexed by bin;
  // 0 out of band).
  std::vector<double> bin_power;
  SignalShare share_finder;
  std::vector<float> share_weight;
  bool share_flat = true;
  std::vector<WindowExtremum> extrema;  // scratch for PickDelayCandidates
  bool have_spectra = false;            // `spectra` hold the last frame Estimate took (MeasureCrossPairs)
  // Two channels per forward transform, two pairs per inverse (packed_transforms.h).
  PackedTransforms packed;
};

}  // namespace localizer::engine
