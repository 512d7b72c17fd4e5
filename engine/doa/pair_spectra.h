// One frame's PHAT cross-spectra for every pair of sensors, the GCC of each as a detection
// field over lags, and the exact GCC at any fractional lag (for refining a direction).
//
// For sensors i < j (pair p, in the order (0,1), (0,2), ..., (1,2), ...), channels zero padded
// to M = NextFastFftSize(N + max lag + 1) samples (no window; N = frame samples):
//     G_p(k) = X_i(k) conj(X_j(k)) / |X_i(k) conj(X_j(k))|        for the B in-band bins k
//     R_p(l) = (1 / B) sum_k Re(G_p(k) exp(2 pi i k l / M))       (l in samples, fractional)
// A source whose sound reaches sensor i at t_i and j at t_j (samples) gives R_p a peak of up
// to 1 at l = t_i - t_j. With independent noise on the channels, R_p(l) at any one lag is
// ~N(0, sigma^2), sigma^2 = (M / N) / (2B): 1 / (2B) for B independent phases, times M / N
// because the zero-padded spectrum has only N degrees of freedom over its M bins (measured:
// without the factor, noise frames passed a 1e-3 threshold 7x too often). The pair's field
// n_p(l) = R_p(l) / sigma is N(0, 1) without a source (lag_field.h). Different pairs are
// uncorrelated under noise (PHAT keeps only phases, independent per channel).
//
// Removing a source (RemoveDelay): the pure-delay component at lag l, weighted per bin by the
// bin's share of signal w_k = 1 - N / P_k (P_k its power over the sensors before PHAT,
// smoothed over neighbouring bins, N the noise level from the frame's quietest bins; 0 at
// the noise level, ~1 where a source dominates; all 1 when the frame's spectrum is flat), c = sum_k w_k G_p(k) e^(2 pi
// i k l / M) / sum_k w_k^2, is subtracted (c w_k per bin), which takes the source's peak and its sidelobes out of R_p
// (CLEAN-style) and leaves the other sources. Unweighted (the plain least-squares pure
// delay), a source that fills part of the band (300-6000 Hz at 16 kHz) was left at 1 - c in
// its bins and at -c in the noise-only ones: two sincs of different widths whose difference
// the next search took for a second source, at 36 % of the first's statistic, in every
// frame. (A band per source, estimated from the aligned spectrum, failed: two sources'
// interference notches it. A hard occupied band, bins 6 dB over the floor, left weak parts of
// a source unremoved in reverberant rooms.)
// Diffuse weighting (PairSpectraOptions::diffuse_distance_m). A room's reverberation is
// close to a diffuse field, whose cross-spectrum across sensors d apart is real:
// Gamma(f) = sinc(2 pi f d / c) (Cook et al. 1955) times its power. Where the pair is
// small against the wavelength Gamma ~ 1, and PHAT turns the reverberation into a phase of 0
// in every such bin: a peak at lag 0 on every pair, which a planar array reads as its
// normal (the zenith) and a linear one as broadside, whatever the talkers' directions. The
// weight v_p = 1 - Gamma_p^2 keeps the bins where the field decorrelates across the pair
// (longer pairs keep lower frequencies: on an 8.1-cm pair 0.17 at 500 Hz, 0.55 at 1 kHz, 0.99
// at 2 kHz). 1 - |Gamma| and (1 - |Gamma|)^2 were measured too: each lost more of the
// talkers (ACCURACY.md, "The room's diffuse sound"). RemoveDelay's model carries the
// same weights.
// Signal weighting (PairSpectraOptions::signal_weighting). PHAT gives every in-band bin the
// same say, and a talker's voiced sound holds a few harmonics below 3 kHz: the bins between
// and above them carry only noise and reverberation, which PHAT adds at full weight. Each
// bin is weighted by its share of signal this frame (w_k below, times the pair's diffuse
// weight), rescaled per pair so that the sum of squared weights is B: the phases of
// noise-only bins do not depend on their magnitudes, so the noise-only deviation stays sigma
// and the presence threshold keeps its false-alarm rate; a frame whose spectrum is flat
// (white sources, or noise alone) has every share 1 and is weighted as without. Measured on
// seeded rooms (ACCURACY.md, "A talker's harmonics: bins weighted by their signal").
// A bin where either channel is silent (|X_i conj(X_j)| below 1e-12 of the frame's mean
// power) contributes 0.
//
// Cost per frame: ceil(sensors / 2) complex FFTs of M (two channels in one), P = sensors
// (sensors - 1) / 2 products over the band and ceil(P / 2) complex inverse FFTs of M (two
// pairs in one; engine/tdoa/packed_transforms.h) (BENCHMARKS.md, doa_bench). Not thread-safe; one per analyser.
#pragma once

#include <complex>
#include <vector>

#include "engine/core/measurement.h"
#include "engine/core/status.h"
#include "engine/core/types.h"
#include "engine/tdoa/fftw_util.h"
#include "engine/tdoa/packed_transforms.h"
#include "engine/tdoa/signal_share.h"

namespace localizer::engine {

struct PairSpectraOptions {
  int sensors = 0;
  int frame_samples = 0;
  double sample_rate_hz = 0.0;
  double band_low_hz = 0.0;   // in-band: low <= f <= high, DC and Nyquist excluded
  double band_high_hz = 0.0;  // 0: up to the Nyquist frequency
  int max_lag_samples = 0;    // the field covers lags [-max_lag, max_lag]
  int rise_lag_frames = 1;    // WholeAt(previous): how many frames back, in [1, 64]
  // Diffuse weighting (empty: off): per pair, in the pairs' order, the distance between its
  // sensors (m), and the speed of sound. Each bin of pair p is weighted by
  // v_p(f) = 1 - sinc^2(2 pi f d_p / c), one less a diffuse field's magnitude-squared
  // coherence across the pair, scaled so that sum_k v_p(f_k)^2 = B (the noise-only
  // deviation stays sigma). See "Diffuse weighting" above.
  std::vector<double> diffuse_distance_m;
  double sound_speed_mps = 343.0;
  // Signal weighting (false: off): each frame's bins weighted by their share of signal (the
  // same share RemoveDelay's model uses), scaled per pair so that sum_k weight^2 = B. See
  // "Signal weighting" above.
  bool signal_weighting = false;
};

class PairSpectra {
 public:
  // INVALID_ARGUMENT naming the option (sensors < 2, no bin in the band, a lag window that
  // does not fit in half the transform, ...).
  static StatusOr<PairSpectra> Create(const PairSpectraOptions& options);

  int pair_count() const { return static_cast<int>(pairs_.size()); }
  // The sensors of pair p: first < second.
  std::pair<int, int> sensors_of(int p) const { return pairs_[static_cast<size_t>(p)]; }
  int fft_size() const { return fft_size_; }
  int band_bins() const { return static_cast<int>(bins_.size()); }

  // The frame: sensors x frame_samples floats, channel-major. INVALID_ARGUMENT on a
  // non-finite sample (naming the sensor). Fills `field` with one PairMeasurement per pair:
  // gcc = R_p at integer lags -max_lag..max_lag, peak_value = sigma (the noise-only
  // deviation) and peak_snr = 1, so that LagField's normalisation gives n_p; sample_rate_hz.
  Status Analyse(const float* frame, Measurement* field);
  // Subtracts pair p's pure-delay component at `lag_samples` from its spectrum and returns
  // the component's amplitude c. At() sees the change at once; the field does after FillFields.
  // `taken` receives the per-bin amplitudes c_k (band_bins() of them).
  void RemoveDelay(int p, double lag_samples, std::vector<std::complex<double>>* taken);
  // Adds back a component RemoveDelay took (the same lag and amplitudes).
  void RestoreDelay(int p, double lag_samples, const std::vector<std::complex<double>>& taken);
  // Every pair's spectrum back to the last analysed frame's whole one (no source removed),
  // so that a caller can remove a chosen set of sources (near-field fits of one source among
  // several, near_field.h). No-op before the first frame.
  void ResetToWhole();
  // Rewrites `field` (as Analyse filled it) from the current spectra: one inverse FFT per pair.
  void FillFields(Measurement* field);
  // The last analysed frame's in-band power: the mean of |X_c(k)|^2 over the sensors and the
  // in-band bins (unnormalised FFT of the frame). What is heard, before PHAT discards it.
  double band_power() const { return band_power_; }
  // The noise-only deviation of R_p at one lag.
  double noise_sigma() const { return noise_sigma_; }

  // R_p at a fractional lag and its first two derivatives per sample, from the spectrum.
  struct Value {
    double r = 0.0, dr = 0.0, d2r = 0.0;
  };
  Value At(int p, double lag_samples) const;
  // R_p at a fractional lag from the whole spectrum of the last analysed frame (no source
  // removed) or, previous = true, of the frame rise_lag_frames before it (0 when there was
  // none). For the rise of a direction between frames (SrpPhat, DirectionPeak::rise).
  double WholeAt(int p, double lag_samples, bool previous) const;
  // The same (this frame's whole spectrum) with its first two derivatives per sample
  // (near-field fits, near_field.h); zero before the first frame.
  Value WholeValueAt(int p, double lag_samples) const;

 private:
  PairSpectra() = default;
  // Pairs p and q (q < 0: p alone) into out->pairs, their inverse transforms packed into one.
  void FillTwoFields(int p, int q, Measurement* out);
  void FillField(int p, const float* correlation, PairMeasurement* out);
  // kDerivatives false: only r (the same value), dr = d2r = 0.
  template <bool kDerivatives = true>
  Value Evaluate(const std::vector<std::complex<double>>& g, double lag_samples) const;
  PairSpectraOptions options_;
  int fft_size_ = 0;
  double noise_sigma_ = 0.0;
  double band_power_ = 0.0;
  std::vector<std::pair<int, int>> pairs_;
  std::vector<int> bins_;                             // in-band bin indices
  std::vector<double> omega_, omega_squared_;         // per in-band bin k: 2 pi k / M, its square
  std::vector<std::vector<std::complex<double>>> g_;  // per pair, per in-band bin
  // Per in-band bin, its share of signal this frame (RemoveDelay; the weights with signal
  // weighting), from bin_power_: the bin's power summed over the sensors (Analyse fills it).
  SignalShare share_finder_;
  std::vector<double> bin_power_;
  std::vector<double> bin_re_, bin_im_;              // per sensor, per in-band bin: the last frame's spectrum
  std::vector<std::vector<double>> diffuse_weight_;  // per pair, per in-band bin: v_p (empty: off)
  // Per pair, per in-band bin: the weight Analyse gave the bin this frame (signal weighting,
  // times the diffuse weight; empty without signal weighting: diffuse_weight_ or 1).
  std::vector<double> applied_weight_;
  std::vector<double> model_weight_;  // per pair, per in-band bin: w_k times the bin's weight (this frame's)
  std::vector<double> model_norm_;    // per pair: sum_k (w_k times the bin's weight)^2
  double share_norm_ = 0.0;           // sum of the shares squared
  bool share_ready_ = false;          // share_finder_ and share_norm_ hold this frame's
  void FindSignalShare();
  // phasor_re_, phasor_im_ = e^(2 pi i k l / M) for every in-band bin k (RemoveDelay's scratch).
  void Phasors(double lag_samples);
  std::vector<double> phasor_re_, phasor_im_;
  // g_ before any removal, for the last rise_lag_frames + 1 frames (a ring; newest_ is this frame's)
  std::vector<std::vector<std::vector<std::complex<double>>>> history_;
  size_t newest_ = 0;
  int64_t frames_analysed_ = 0;
  FftwFloats spectra_, cross_, cross_b_;
  PackedTransforms packed_;  // two channels per forward transform, two pairs per inverse
};

}  // namespace localizer::engine
