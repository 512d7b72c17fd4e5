// Generalised cross-correlation TDOA estimation (Knapp & Carter 1976) with FFTW3, float.
//
// For the reference channel x_r and channel x_k, both zero padded to N samples, with
// spectra X_r, X_k:
//     G(f)   = X_k(f) conj(X_r(f)) * W(f) * B(f)
//     R(tau) = IFFT(G)(tau) / S        peaks at tau = delay (x_k(t) = x_r(t - delay))
// N is the smallest 2^a, 3 * 2^a or 5 * 2^a >= frame_samples + max_p L_p + kPeakHalfWidth + 1
// (fftw_util.h): the circular correlation then equals the linear one at every lag the stage
// reads (an alias of lag l lies at l -/+ N, beyond the frame), at about half the cost of
// N = 2 * frame (5120 instead of 8192 for a 4096 frame). Negative lags wrap to the end of the inverse
// transform's output; lags far outside the window are circular and only the quality
// fallback below looks at them.
// Weightings W(f):
//     PHAT       1 / |X_k X_r*|                   (default; whitens, sharp peak)
//     PHAT-beta  1 / |X_k X_r*|^beta               (beta in [0, 1]; 1 = PHAT, 0 = CC)
//     SCOT       1 / sqrt(|X_k|^2 |X_r|^2)  computed per frame (no averaging)
//     CC         1                                (plain cross-correlation)
//     PHAT-coherence  w(f) / |X_k X_r*|  with w learnt over the pair's earlier frames (below)
// Per frame, without averaging, SCOT equals PHAT except in floored bins (it floors each
// auto-spectrum rather than the cross-spectrum). PHAT-beta evaluates |.|^-beta with the
// vectorised FastExp/FastLog of engine/core/fast_math.h (~1e-5 relative), not powf.
// B(f) is 1 inside the optional band [band_low_hz, band_high_hz] and 0 outside. Set it to
// the source's band: PHAT weighs every bin alike, so bins without source energy only add
// noise (peak_interpolation.h measures the spread with and without it).
// A small floor (1e-12 of the frame's mean power, in the units of the quantity floored:
// |X_k X_r*| >= 1e-12 sqrt(E_k E_r), |X_k|^2 >= 1e-12 E_k, E = sum of squared samples, which
// by Parseval is the mean of |X|^2 over the N bins; never below FLT_MIN) keeps silent bins
// finite.
//
// Normalisation: S = sum over all N bins (the full Hermitian spectrum) of |G(f)|. By the
// triangle inequality |R(tau)| <= 1 for every weighting, and R(delay) = 1 for a perfect
// single path (X_k = X_r exp(-j 2 pi f delay) in every in-band bin); for PHAT S is the
// number of in-band bins of the full spectrum (less what the floor removes). On a real
// frame a clean delayed copy peaks a little lower: by |delay| / frame (the windows' ends
// that do not overlap), by the share of bins without source energy that PHAT whitens, and
// because peak_value is read at the integer lag (0.4 sample off the true delay, a
// 200..4000 Hz GCC at 11025 Hz is down to 0.86). A frame with no energy in the band gives
// S = 0: every pair then reports delay 0, quality 0, peak_value 0 and an all-zero GCC.
//
// The peak (largest R, not |R|) is searched only over |lag| <= L_p,
//     L_p = min(ceil(max_delay_s(pair) * fs) + lag_margin_samples, N/2 - 1 - kPeakHalfWidth)   [samples]
// and refined to a sub-sample lag by options.interpolation (see peak_interpolation.h for the
// methods and their measured bias); the refined offset is at most one sample from the
// integer peak, so a peak on the window's edge may refine just beyond it.
// Quality = peak / largest |R| outside the main lobe within the window, where the main lobe
// is the run of samples either side of the peak that stay positive and keep falling (it ends
// at the first zero crossing or the first local minimum). When the main lobe fills the whole
// window, the largest |R| over the rest of the full correlation is used instead. Quality is
// capped at 1e9 and can fall below 1 when a negative lobe, or (in that fallback) a peak
// outside the window, is larger than the peak: treat small values as "no clear peak".
// peak_value is R at the integer peak; peak_snr = peak_value * sqrt(2 * in-band bins), its
// ratio to the noise-only standard deviation of R (measurement.h). With keep_gcc, pair.gcc holds R (same
// normalisation) at lags -L_p..L_p, so first_lag_samples = -L_p and gcc.size() = 2 L_p + 1.
//
// delay_sigma_s, the standard deviation of this frame's delay. Near the peak d, with
// A_k = G_k exp(j w_k d) = Re_k + j Im_k (w_k = 2 pi k / N rad/sample, c_k = 2 for the bins
// that stand for a conjugate pair, 1 for DC and Nyquist):
//     R'(tau)  = -(1/S) sum c_k w_k Im(G_k e^{j w_k tau}),  R''(d) = -(1/S) sum c_k w_k^2 Re_k.
// The refined delay solves R'(d_hat) = 0, so to first order d_hat - d = -R'(d) / R''(d). The
// signal's part of Im_k vanishes at the true delay; what is left is noise, so
//     var R'(d) = (N / M) (1/S^2) sum c_k^2 w_k^2 E[Im_k^2]
// (N / M = fft_size / frame_samples: zero padding makes ~N/M neighbouring bins one independent
// one), and E[Im_k^2] is estimated by this frame's Im_k^2 at the refined delay. Hence
//     sigma = sqrt((N / M) sum c_k^2 w_k^2 Im_k^2) / sum c_k w_k^2 Re_k    [samples],
// S cancelling; then the interpolator's error is added in quadrature (kSinc: 0.002 sample, its
// rms on clean frames; kParabolic / kGaussian: their distance from the kSinc refinement of the
// same samples, i.e. their bias on this peak, which is 0.04-0.06 sample at 11 kHz and much less
// on a wide peak), and sigma is capped at (2 L_p + 1) / sqrt(12), a delay uniform over the
// window (also what a frame with no energy in the band reports). With noise-only bins
// (E[Im^2] = 1/2 for PHAT) this is the quadratic-peak argument 1 / (peak_snr sqrt(-R''/R))
// times sqrt(N/M); at high SNR Im_k shrinks with the per-bin phase noise, so, unlike that
// formula, sigma keeps falling with SNR (it would otherwise overstate a 20 dB frame 10x).
// Measured (tests/tdoa/gcc_frontend_test.cc, DelaySigma.AgreesWithTheMeasuredSpread; 24
// frames x 3 pairs per point, rms of sigma over rms error about the truth):
//     scene                                 -5 dB  0 dB   5 dB   10 dB  20 dB
//     11025 Hz, 200-4000 Hz, band set        1.06   1.10   1.11   1.18   1.26 (sinc floor)
//     same, no band (PHAT whitens noise)     0.99   0.99   0.99   0.99   0.92
//     same, band set, kParabolic             0.94   0.96   0.99   1.00   1.00
//     48 kHz, 300-3000 Hz, 8192, band set    0.90   0.96   1.03   1.08   1.14
// Spreads at 0 dB: 0.023, 0.045, 0.055, 0.109 sample. At -10 dB without a band, or at 48 kHz
// without a band, peaks are lost (a third of the pairs at 48 kHz) and sigma is then large,
// usually the cap: it describes the scatter about the peak found, not whether that peak is the
// source (peak_snr and quality say that). Cost: one pass over the in-band bins per pair
// (phasor rotated in 16 double lanes): gcc_bench's stage_over_bare went from 1.11-1.13
// (BENCHMARKS.md) to 1.48-1.59 (91-96 us against 60-62 us of bare transforms, 4 x 4096,
// FFTW_ESTIMATE, on a loaded shared machine), i.e. ~10 us per pair for sigma and candidates.
//
// candidates: the local extrema of R in the window (maxima with R > 0 and minima with R < 0:
// an inverted copy, e.g. an echo off a pressure-release surface, is a negative extremum),
// candidates[0] the main peak, the others by decreasing |R|, up to max_candidates, each at least
// one envelope width from those taken: 2 pi / (sqrt(12) sigma_w) lags, sigma_w the rms width of
// the aligned spectrum Re_k (the first null of a flat band's envelope; 2.9 samples for
// 200-4000 Hz at 11025 Hz), so the carrier ripples of one peak are not candidates. Each is
// refined by options.interpolation (on -R for a minimum); its delay_sigma_s uses the same
// var R'(d) over the sinc reconstruction's curvature at that candidate. Measured: direct path
// + echo (gain -0.9, 9 samples later) at 20 dB gives the direct path first (R 0.66) and the
// echo second (R -0.48) in 10 of 10 frames.
//
// PHAT-coherence (weighting kPhatCoherence): PHAT whitens bins that hold only noise, which is
// why without the band the spread grows several-fold. After each frame the pair's cross-spectrum
// is aligned by that frame's measured delay d and each in-band bin's
//     c_k = Re(X_k X_r* e^{j w_k d}) / |X_k X_r*|
// (~1 where the source dominates; cos of a uniform phase, mean 0, where noise does: whatever the
// source's motion, since every frame aligns by its own delay) is folded into an exponential
// average with time constant coherence_time_constant_frames (bias-corrected for the first
// frames), box-smoothed over +-coherence_smoothing_bins bins; the next frame's bins are weighted
//     w = C / (1 - C),  C = clamp(c_smooth^2 - v0, 0, 0.98)
// (Knapp & Carter's ML weight |gamma|^2 / (1 - |gamma|^2) in coherence terms), v0 being the
// expected c^2 of a noise-only bin for this many frames and smoothed bins, so that such bins get
// weight ~0. peak_snr divides by the weights' own noise-only scale (effective bins
// (sum w)^2 / sum w^2, which falls far below the band's bins once the weights gather on the
// source's), so the presence test's null holds for them as for PHAT (white noise streamed at a
// half-frame hop: 95th percentile 3.2, as PHAT's; 11.2 with PHAT's scale). The first
// coherence_warmup_frames frames of each pair use plain PHAT. S still
// normalises, so R(d) = 1 for a perfect path. The coherence is learnt from the unweighted
// spectra, so a bin weighted to zero can come back. The state is per estimator and per pair:
// frames must be given in time order, a fresh estimator (or one after Reset()) replays a stream
// bit for bit, and a dropped or reordered frame only perturbs the average.
// Measured (PhatCoherence.WithoutABandHintMatchesPhatWithTheTrueBand; 500-2000 Hz source,
// white noise 0-5.5 kHz, 11025 Hz, 40 scored frames x 3 pairs after 8 warm-up):
//     SNR      PHAT, true band   PHAT, no band        PHAT-coherence, no band
//     -10 dB   0.180 (0 lost)    0.457 (9 lost)       0.206 (0 lost)
//      -5 dB   0.083             0.306                0.088
//       0 dB   0.047             0.234                0.047
// i.e. within 1.15x of PHAT with the true band, 2.2-5x better than PHAT without it. Cost:
// the weight array read in the weighing pass plus one O(bins) update per pair and frame:
// BM_GccPhatCoherence 133 us per 4 x 4096 frame against 91-96 us for PHAT (same run).
//
// PHAT-share (weighting kPhatShare): each frame, every channel's power is summed per bin (every
// bin, so that a band hint's floor is read beside it) and each bin's share of signal found,
// s = max(0, 1 - k N / P) (signal_share.h: P the bin's power over 3 bins, N the 10th
// percentile of the 33-bin average, k read from the noise's own statistics for this many
// channels); each in-band bin is weighted W = w / |G| with
// w = s^2 / (1 - s^2), at most 4: the maximum-likelihood weight for two channels whose
// coherence is s (gcc_weighing.cc), which leaves noise bins almost nothing. Cross pairs alike.
// No band hint and no memory between frames: a frame that does not show its band (no 33-bin
// average stands out of the noise's own spread: white sound, noise alone, or a source a few
// dB under the noise in its own bins) is weighed exactly as PHAT. peak_snr divides by the
// weights' own noise-only scale, as kPhatCoherence's. Measured (tests/tdoa/phat_share_test.cc,
// rms delay error in samples): the source and noise of PHAT-coherence's measurement above,
// -5 dB 0.089 (PHAT with the true band 0.091, without 0.318), 0 dB 0.039 (0.045, 0.227), -10 dB
// as PHAT without the band; a 300-3000 Hz source at 48 kHz (8192-sample frames) 0 dB 0.099
// (PHAT with the band 0.109), 20 dB 0.021 (0.015), where w = s gave 2.2x and 10.9x the band's.
// On the random campaign, without a band hint, the median RMSE over the theoretical bound
// comes within a few per cent of the true band's (ACCURACY.md, "Thirty-first pass"). Cost:
// one pass over the channels' bins, two partial sorts and two running means per frame
// (BM_GccPhatShare, about 10 us per 4 x 4096 frame over PHAT).
//
// Cost per frame: ceil(channels / 2) complex FFTs of N (two channels in one, packed_transforms.h)
// plus ceil((channels - 1) / 2) complex inverse FFTs of N (two pairs in one; the cross pairs,
// GccOptions::cross_pairs_max_sensors, add one weighing each and share the inverse transforms),
// O(N) to pack and unpack them, O(N) for the spectra (one vectorised pass per pair,
// cross_spectrum.h), O(L_p) for the peak and
// ~0.2 us per pair for the sinc refinement; plans are made once in Create and reused, so
// Estimate allocates nothing after the first call (which sizes out->pairs and each pair's
// gcc). tests/bench/gcc_bench.cc compares Estimate with the bare transforms.
// out->t_s is the caller's t_s (the frame centre); see measurement.h for the instant each
// pair describes.
//
// FFT plans are FFTW_ESTIMATE by default: planning takes milliseconds and the plan is the same
// in every process, so a session replays bit for bit. measure_fft_plans = true uses
// FFTW_MEASURE: on the build machine the N = 8192 transforms ran ~20-25% faster, but
// planning takes ~0.5 s per new size per process and the chosen plan (hence the last bits of
// the results) may differ between processes. Caveat: FFTW keeps process-wide wisdom, and an
// FFTW_ESTIMATE plan reuses what an earlier FFTW_MEASURE plan of the same size found, so
// replay is bit-exact only if a process never mixes the two (pick one per process).
// Create and the destructor may run on any thread (FFTW's planner is guarded by a mutex);
// Estimate on one estimator must not run concurrently with itself.
#pragma once

#include <memory>
#include <string>

#include "engine/array/array_geometry.h"
#include "engine/tdoa/peak_interpolation.h"
#include "engine/tdoa/tdoa_estimator.h"

namespace localizer::engine {

enum class Weighting { kPhat, kPhatBeta, kScot, kCc, kPhatCoherence, kPhatShare };

// Parses "phat", "phat-beta", "scot", "cc", "phat-coherence", "phat-share"; anything else is
// INVALID_ARGUMENT listing them.
StatusOr<Weighting> ParseWeighting(const std::string& name);
const char* WeightingName(Weighting w);

struct GccOptions {
  int frame_samples = 4096;     // samples per channel per frame, in [64, 2^20]
  double sample_rate_hz = 0.0;  // > 0, finite
  Weighting weighting = Weighting::kPhat;
  double phat_beta = 0.8;      // only used by kPhatBeta; must be in [0, 1]
  double band_low_hz = 0.0;    // 0: from DC; in [0, fs/2), < band_high_hz when that is set
  double band_high_hz = 0.0;   // 0: up to Nyquist; else in (band_low_hz, fs/2]
  int lag_margin_samples = 2;  // searched beyond the physical maximum delay, >= 0
  // Share of each frame tapered (a Tukey window, gcc_math.h's TaperGain: half cosines over
  // the first and last taper_fraction / 2 of the samples), in [0, 1]; 0: a rectangle, 1: a
  // Hann window. Why: a rectangular frame cuts the signal at its ends, where a delayed copy's
  // samples have no partner in the other channel, and that scatters the peak
  // (tests/tdoa/peak_interpolation_test.cc, sinc refinement, rms over fractional delays):
  //   noiseless, band set          0.00148 sample -> 0.00035 at 0.2 (0.00020 with Hann)
  //   20 dB, no band               0.0174 -> 0.0153 at 0.2 (0.0210 with Hann: the window's
  //                                loss of samples costs more than its ends gain)
  //   noiseless, no band           0.116 -> 0.135 at 0.2 (0.049 with Hann)
  // Random campaign, ten draws of 200 scenes, no band hint (ACCURACY.md, "Twentieth pass"):
  // Gaussian RMSE/CRLB 0.585 -> 0.564 (median of draws, better in 8 of 10), silent failures
  // 12 -> 10, acquired 1975 -> 1972, within 3 x the theoretical CRLB 841 -> 829, p95 time to
  // acquire 6.1 -> 6.7 s (median of draws; worst 9.1 -> 7.5): beyond the Gaussian ratio,
  // within the draws' noise. A session sets it from its framing (session_config.h,
  // FramingTaperFraction: Hann at 50 % overlap, which did better still); 0.2 is for a frame
  // that no other overlaps. The noise floor behind peak_snr and presence follows the taper
  // (gcc_layout.h), so pure noise reads the same through any of them.
  double taper_fraction = 0.2;
  bool keep_gcc = true;                                        // copy the GCC over the lag window into the Measurement
  PeakInterpolation interpolation = PeakInterpolation::kSinc;  // sub-sample refinement
  bool measure_fft_plans = false;                              // FFTW_MEASURE instead of FFTW_ESTIMATE (see above)
  int max_candidates = 4;  // PairMeasurement::candidates per pair, in [1, 32]; 1: the
                           // main peak only
  // Arrays of at most this many sensors (in [0, 16]; 0: never) can also measure every pair of
  // non-reference sensors, into Measurement::cross_pairs, on request (MeasureCrossPairs; only
  // with keep_gcc; their GCC over the lag window and noise scale, no peak): (S - 1)(S - 2) / 2
  // more weighings and inverse transforms, 3 for 4 sensors (+11 us on a 4 x 4096 frame at
  // 44.1 kHz, about a quarter of the stage). Why: a 4-sensor array's three reference pairs have an exact
  // solution whatever one of them measured, so a pair on an echo or a noise peak moves the
  // fix without a trace in any residual; with the other three pairs, acquisition and presence
  // (lag_field.h) see it. A cross pair's window is clamped where the transform's circular
  // correlation would alias (N - frame_samples - kPeakHalfWidth - 1 lags; gcc_layout.h).
  // kPhatCoherence weighs cross pairs with plain PHAT.
  int cross_pairs_max_sensors = 0;
  // Estimate measures the cross pairs too (when the array has them and no delay rates are
  // set; else they stay on request), their inverse transforms packed with the reference
  // pairs' (packed_transforms.h): for 4 sensors three complex inverse transforms per frame
  // instead of four. For a caller that reads them on every frame (a session with
  // pair_closure).
  bool cross_pairs_with_frame = false;
  // kPhatCoherence: the exponential average's time constant in frames (>= 1; the weight of
  // a frame falls by e after this many frames) and the frames measured with plain PHAT before
  // the averaged coherence is used (>= 1).
  double coherence_time_constant_frames = 16.0;
  int coherence_warmup_frames = 4;
  int coherence_smoothing_bins = 8;  // kPhatCoherence: half-width of the box average of the
                                     // coherence over frequency, bins, in [0, 4096]

  // OK, or INVALID_ARGUMENT naming the field and value.
  Status Validate() const;
};

class GccPhatEstimator final : public TdoaEstimator {
 public:
  // INVALID_ARGUMENT when options.Validate() fails or the band holds no FFT bin; INTERNAL
  // when FFTW cannot plan.
  static StatusOr<std::unique_ptr<GccPhatEstimator>> Create(const ArrayGeometry& array, const GccOptions& options);
  ~GccPhatEstimator() override;
  GccPhatEstimator(const GccPhatEstimator&) = delete;
  GccPhatEstimator& operator=(const GccPhatEstimator&) = delete;

  // INVALID_ARGUMENT (naming the value) when frame or out is null, frame_samples differs from
  // options().frame_samples, or a channel holds a non-finite sample; `out` is then untouched.
  Status Estimate(const float* frame, int frame_samples, double t_s, Measurement* out) override;
  // The last estimated frame's pairs without the reference (GccOptions::cross_pairs_max_sensors;
  // none for larger arrays or without keep_gcc). Estimate leaves out->cross_pairs empty
  // unless cross_pairs_with_frame; FAILED_PRECONDITION before a frame was estimated (or after
  // one that failed).
  Status MeasureCrossPairs(Measurement* out) override;
  // From the next Estimate on, each pair with a rate other than 0 is measured twice: as the
  // frame is, and with its sensor's channel read along the rate (delay_warp.h); it keeps the
  // reading whose peak is higher (a right rate sharpens a migrating peak, a wrong one smears
  // it further), and the cross pairs use the kept readings' spectra. The extra cost is one
  // forward transform and one pair's weighing per such pair, on those frames only. Ignored
  // with kPhatCoherence (which learns from each pair it measures). INVALID_ARGUMENT (nothing
  // changed) unless empty or one finite rate per pair with |rate| < 0.05 (2 v / c for
  // 8.6 m/s in air, 37 m/s in water).
  Status SetDelayRates(std::span<const double> rate_per_pair) override;

  // Forgets what kPhatCoherence learnt (the next frame starts its warm-up): the estimator
  // then answers like a fresh one. A no-op for the other weightings.
  void Reset();

  const GccOptions& options() const;
  int fft_size() const;                 // N
  int max_lag_samples(int pair) const;  // L_p, the half-width of the searched window

 private:
  struct Impl;
  explicit GccPhatEstimator(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace localizer::engine
