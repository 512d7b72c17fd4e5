#include "engine/tdoa/gcc_phat.h"

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numbers>
#include <span>
#include <string>
#include <vector>

#include "engine/tdoa/cross_spectrum.h"
#include "engine/tdoa/fftw_util.h"
#include "engine/tdoa/gcc_layout.h"

namespace localizer::engine {
namespace {

constexpr int kMinFrameSamples = 64;
constexpr int kMaxFrameSamples = 1 << 20;
constexpr int kMaxCandidates = 32;
// The envelope of a flat band of width B (rad/sample) is sinc-like with its first null at
// 2 pi / B = (2 pi / sqrt(12)) / sigma_omega, sigma_omega = B / sqrt(12) its rms width.
constexpr double kEnvelopeNullPerRmsWidth = 2.0 * std::numbers::pi / 3.4641016151377544;

// The sinc interpolator's own rms error on a clean frame (peak_interpolation.h: 0.0011 sample
// noiseless, rounded up), added in quadrature to delay_sigma: the statistical part alone
// would claim less than the method delivers on a clean frame.
constexpr double kSincFloorSamples = 0.002;

// The refinement's systematic error on this peak: for kParabolic and kGaussian their distance
// from the (nearly unbiased) kSinc refinement of the same samples, which is their bias here
// (0.04-0.06 sample at 11 kHz, far less on a peak many samples wide); kSinc's floor else.
double InterpolationErrorSamples(PeakInterpolation method, std::span<const float, kPeakSamples> samples,
                                 double offset) {
  if (method == PeakInterpolation::kSinc) return kSincFloorSamples;
  const double bias = offset - InterpolatePeak(PeakInterpolation::kSinc, samples);
  return std::sqrt(bias * bias + kSincFloorSamples * kSincFloorSamples);
}

std::string Value(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", v);
  return text;
}

Status BadOption(const char* field, const std::string& value, const std::string& rule) {
  return InvalidArgument(std::string("GccOptions.") + field + " is " + value + "; " + rule);
}
Status BadOption(const char* field, double value, const std::string& rule) {
  return BadOption(field, Value(value), rule);
}
Status BadOption(const char* field, int value, const std::string& rule) {
  return BadOption(field, std::to_string(value), rule);
}

// Copies one channel into the zero-padded transform input and returns its energy (sum of
// squares, double so that no finite input overflows). Partial sums in kLanes lanes let the
// compiler vectorise the reduction without reassociating a single float sum.
double CopyChannel(const float* src, int n, float* dst) {
  double lanes[kLanes] = {};
  int i = 0;
  for (; i + kLanes <= n; i += kLanes) {
    for (int j = 0; j < kLanes; ++j) {
      const float v = src[i + j];
      dst[i + j] = v;
      lanes[j] += static_cast<double>(v) * v;
    }
  }
  double energy = 0.0;
  for (; i < n; ++i) {
    dst[i] = src[i];
    energy += static_cast<double>(src[i]) * src[i];
  }
  for (double lane : lanes) energy += lane;
  return energy;
}

int ArgMax(std::span<const float> r) { return static_cast<int>(std::max_element(r.begin(), r.end()) - r.begin()); }

float MaxAbs(std::span<const float> r) {
  float best = 0.0f;
  for (float v : r) best = std::max(best, std::abs(v));
  return best;
}

// The fallback for a window that is all main lobe: the same lobe rule on the full circular
// correlation of length n (gcc_math.h), and the largest |R| outside it.
float LargestOutsideLobe(const float* corr, int n, int peak_lag) {
  const auto at = [&](int lag) { return corr[WrapLag(lag, n)]; };
  int first, last;
  CircularMainLobe(at, n, peak_lag, &first, &last);
  float best = 0.0f;
  for (int lag = last + 1; lag < first + n; ++lag) best = std::max(best, std::abs(at(lag)));
  return best;
}

}  // namespace

// ---- Names and options ------------------------------------------------------------------

StatusOr<Weighting> ParseWeighting(const std::string& name) {
  if (name == "phat") return Weighting::kPhat;
  if (name == "phat-beta") return Weighting::kPhatBeta;
  if (name == "scot") return Weighting::kScot;
  if (name == "cc") return Weighting::kCc;
  if (name == "phat-coherence") return Weighting::kPhatCoherence;
  return InvalidArgument("weighting \"" + name +
                         "\" is not one of \"phat\", \"phat-beta\", \"scot\", \"cc\", "
                         "\"phat-coherence\"");
}

const char* WeightingName(Weighting w) {
  switch (w) {
    case Weighting::kPhat:
      return "phat";
    case Weighting::kPhatBeta:
      return "phat-beta";
    case Weighting::kScot:
      return "scot";
    case Weighting::kCc:
      return "cc";
    case Weighting::kPhatCoherence:
      return "phat-coherence";
  }
  return "unknown";
}

Status GccOptions::Validate() const {
  if (frame_samples < kMinFrameSamples || frame_samples > kMaxFrameSamples) {
    return BadOption("frame_samples", frame_samples,
                     "must be in [" + std::to_string(kMinFrameSamples) + ", " + std::to_string(kMaxFrameSamples) + "]");
  }
  if (!(sample_rate_hz > 0.0) || !std::isfinite(sample_rate_hz)) {
    return BadOption("sample_rate_hz", sample_rate_hz, "must be positive and finite");
  }
  const double nyquist_hz = 0.5 * sample_rate_hz;
  if (!(band_low_hz >= 0.0) || !(band_low_hz < nyquist_hz)) {
    return BadOption("band_low_hz", band_low_hz, "must be in [0, sample_rate_hz / 2 = " + Value(nyquist_hz) + ")");
  }
  if (!(band_high_hz >= 0.0) || !(band_high_hz <= nyquist_hz)) {
    return BadOption("band_high_hz", band_high_hz,
                     "must be 0 (up to Nyquist) or in (band_low_hz, sample_rate_hz / 2 = " + Value(nyquist_hz) + "]");
  }
  if (band_high_hz > 0.0 && !(band_high_hz > band_low_hz)) {
    return BadOption("band_high_hz", band_high_hz, "must exceed band_low_hz = " + Value(band_low_hz));
  }
  if (!(phat_beta >= 0.0 && phat_beta <= 1.0)) {
    return BadOption("phat_beta", phat_beta, "must be in [0, 1]");
  }
  if (lag_margin_samples < 0) {
    return BadOption("lag_margin_samples", lag_margin_samples, "must be >= 0");
  }
  if (max_candidates < 1 || max_candidates > kMaxCandidates) {
    return BadOption("max_candidates", max_candidates, "must be in [1, " + std::to_string(kMaxCandidates) + "]");
  }
  if (!(coherence_time_constant_frames >= 1.0) || !std::isfinite(coherence_time_constant_frames)) {
    return BadOption("coherence_time_constant_frames", coherence_time_constant_frames, "must be finite and >= 1");
  }
  if (coherence_smoothing_bins < 0 || coherence_smoothing_bins > 4096) {
    return BadOption("coherence_smoothing_bins", coherence_smoothing_bins, "must be in [0, 4096]");
  }
  if (coherence_warmup_frames < 1) {
    return BadOption("coherence_warmup_frames", coherence_warmup_frames, "must be >= 1");
  }
  return Status::Ok();
}

// ---- Estimator ----------------------------------------------------------------------------

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

Status GccPhatEstimator::Impl::Init() {
  auto computed = ComputeGccLayout(array, options);
  if (!computed.ok()) return computed.status();
  layout = std::move(computed).value();
  const int fft_size = layout.fft_size;
  spectrum_stride = (2 * layout.bin_count + 15) / 16 * 16;
  const int widest_lag = layout.widest_lag();
  window.assign(2 * (widest_lag + kPeakHalfWidth) + 1, 0.0f);
  energy.assign(array.sensor_count(), 0.0);

  padded = AllocateFftwFloats(fft_size);
  spectra = AllocateFftwFloats(static_cast<std::size_t>(spectrum_stride) * array.sensor_count());
  cross = AllocateFftwFloats(2 * layout.bin_count);
  corr = AllocateFftwFloats(fft_size);
  weighed = AllocateFftwFloats(2 * layout.bin_count);
  if (options.weighting == Weighting::kPhatCoherence) {
    const std::size_t cells = static_cast<std::size_t>(array.pair_count()) * layout.bin_count;
    coherence.assign(cells, 0.0f);
    coherence_weight.assign(cells, 0.0f);
    coherence_frames.assign(array.pair_count(), 0);
    coherence_usable.assign(array.pair_count(), 0);
  }
  extrema.reserve(2 * widest_lag + 1);
  const unsigned flags = options.measure_fft_plans ? FFTW_MEASURE : FFTW_ESTIMATE;
  forward = PlanRealForward(fft_size, padded.get(), spectra.get(), flags);
  inverse = PlanRealInverse(fft_size, cross.get(), corr.get(), flags);
  if (!forward || !inverse) {
    return Internal("FFTW could not plan real transforms of size " + std::to_string(fft_size));
  }
  // FFTW_MEASURE scribbles on the arrays while planning; the padding must start at zero.
  std::memset(padded.get(), 0, sizeof(float) * fft_size);
  return Status::Ok();
}

// r2c of one channel into its slot in `spectra`. The padded tail stays zero: out-of-place
// r2c preserves its input, and only the first frame_samples are ever written.
Status GccPhatEstimator::Impl::TransformChannel(const float* samples, int channel) {
  const double e = CopyChannel(samples, options.frame_samples, padded.get());
  if (!std::isfinite(e)) {
    return InvalidArgument("channel " + std::to_string(channel) + " holds a non-finite sample (NaN or Inf)");
  }
  energy[channel] = e;
  float* spectrum = spectra.get() + static_cast<std::size_t>(channel) * spectrum_stride;
  fftwf_execute_dft_r2c(forward.get(), padded.get(), AsComplex(spectrum));
  return Status::Ok();
}

// Fills `cross` with G = W X_k conj(X_r) B and returns S, the sum of |G| over all N bins.
float GccPhatEstimator::Impl::WeighCrossSpectrum(int pair) {
  const int ref = array.reference_sensor();
  const int sensor = array.sensor_of_pair(pair);
  const float* xr = spectra.get() + static_cast<std::size_t>(ref) * spectrum_stride;
  const float* xk = spectra.get() + static_cast<std::size_t>(sensor) * spectrum_stride;
  float* g = cross.get();
  // Out-of-band bins are zeroed every time: c2r destroys its input.
  const int bin_count = layout.bin_count;
  std::memset(g, 0, sizeof(float) * 2 * layout.band_first_bin);
  std::memset(g + 2 * layout.band_end_bin, 0, sizeof(float) * 2 * (bin_count - layout.band_end_bin));

  const double e_ref = energy[ref];
  const double e_sensor = energy[sensor];
  const float floor_mag = PowerFloor(std::sqrt(e_ref * e_sensor));
  const int lo = layout.band_first_bin;
  const int hi = layout.band_end_bin;
  float half_sum = 0.0f;
  switch (options.weighting) {
    case Weighting::kPhat:
      half_sum = WeighBins(xr, xk, lo, hi, PhatWeight{floor_mag}, g);
      break;
    case Weighting::kPhatBeta:
      half_sum = WeighBins(xr, xk, lo, hi, PhatBetaWeight{floor_mag, static_cast<float>(options.phat_beta)}, g);
      break;
    case Weighting::kScot:
      half_sum = WeighBins(xr, xk, lo, hi, ScotWeight{PowerFloor(e_ref), PowerFloor(e_sensor)}, g);
      break;
    case Weighting::kCc:
      half_sum = WeighBins(xr, xk, lo, hi, CcWeight{}, g);
      break;
    case Weighting::kPhatCoherence:
      if (coherence_usable[pair]) {
        const float* w = coherence_weight.data() + static_cast<std::size_t>(pair) * bin_count;
        half_sum = WeighBins(xr, xk, lo, hi, CoherencePhatWeight{floor_mag, w}, g);
      } else {  // warming up: plain PHAT
        half_sum = WeighBins(xr, xk, lo, hi, PhatWeight{floor_mag}, g);
      }
      break;
  }
  // Bins 1..N/2-1 stand for two bins of the full spectrum; DC and Nyquist (real) for one.
  return 2.0f * half_sum - std::abs(g[0]) - std::abs(g[2 * (bin_count - 1)]);
}

// window[i] = R(i - L - K) * scale: the searched lags plus kPeakHalfWidth either side for
// the interpolator. Lags wrap modulo N; L + K < N keeps both runs inside `corr`.
void GccPhatEstimator::Impl::GatherWindow(int max_lag, float scale) {
  const int reach = max_lag + kPeakHalfWidth;
  const float* negative = corr.get() + layout.fft_size - reach;  // lags -reach .. -1
  float* w = window.data();
  for (int i = 0; i < reach; ++i) w[i] = negative[i] * scale;
  const float* positive = corr.get();  // lags 0 .. reach
  for (int i = 0; i <= reach; ++i) w[reach + i] = positive[i] * scale;
}

// Largest |R| outside the main lobe within the window, or, when the lobe fills the window,
// outside it in the whole correlation (scaled like the window).
float GccPhatEstimator::Impl::LargestSidelobe(std::span<const float> searched, int peak, int peak_lag,
                                              float scale) const {
  int first, last;
  MainLobe([&](int i) { return searched[i]; }, static_cast<int>(searched.size()), peak, &first, &last);
  if (first > 0 || last + 1 < static_cast<int>(searched.size())) {
    return std::max(MaxAbs(searched.first(first)), MaxAbs(searched.subspan(last + 1)));
  }
  return scale * LargestOutsideLobe(corr.get(), layout.fft_size, peak_lag);
}

// One pass over the in-band bins of the kept cross-spectrum, rotated to the measured delay
// d: A_k = G_k exp(j w_k d) = Re_k + j Im_k, w_k = 2 pi k / N (rad/sample), c_k = 2 for
// the bins that stand for a conjugate pair and 1 for DC and Nyquist. With kPhatCoherence it
// also folds this frame's aligned coherence Re(X_k X_r* e^{j w_k d}) / |X_k X_r*| into the
// pair's running average.
GccPhatEstimator::Impl::SpectrumStats GccPhatEstimator::Impl::AnalyseSpectrum(int pair, double delay_samples) {
  const int n = layout.fft_size;
  const int lo = layout.band_first_bin;
  const int hi = layout.band_end_bin;
  const double bin_rate = 2.0 * std::numbers::pi / n;
  const float* g = weighed.get();
  const float* xr = spectra.get() + static_cast<std::size_t>(array.reference_sensor()) * spectrum_stride;
  const float* xk = spectra.get() + static_cast<std::size_t>(array.sensor_of_pair(pair)) * spectrum_stride;
  const bool learn = options.weighting == Weighting::kPhatCoherence;
  float* average = learn ? coherence.data() + static_cast<std::size_t>(pair) * layout.bin_count : nullptr;
  const float alpha = static_cast<float>(1.0 / options.coherence_time_constant_frames);
  const double step_angle = bin_rate * delay_samples;
  SpectrumStats stats;
  // The phasor exp(j w_k d) in kLanes independent lanes (lane l at bin first + l), each
  // rotated by exp(j kLanes w_1 d) per block so that the loop vectorises; restarted exactly
  // every 2048 bins (the recurrence then drifts by < 1e-12). Lane sums, reduced at the end.
  constexpr int kRestart = 2048;
  static_assert(kRestart % kLanes == 0);
  const double block_re = std::cos(step_angle * kLanes);
  const double block_im = std::sin(step_angle * kLanes);
  double ph_re[kLanes], ph_im[kLanes];
  double level[kLanes] = {}, first_moment[kLanes] = {}, curvature[kLanes] = {}, slope[kLanes] = {};
  for (int first = lo; first < hi; first += kRestart) {
    const int last = std::min(first + kRestart, hi);
    for (int l = 0; l < kLanes; ++l) {
      ph_re[l] = std::cos(step_angle * (first + l));
      ph_im[l] = std::sin(step_angle * (first + l));
    }
    for (int b = first; b < last; b += kLanes) {
      const int count = std::min(kLanes, last - b);
      // One bin's moments; the full-width call has a constant trip count and vectorises.
      const auto accumulate = [&](int l) {
        const int k = b + l;
        const double gr = g[2 * k];
        const double gi = g[2 * k + 1];
        const double re = gr * ph_re[l] - gi * ph_im[l];
        const double im = gr * ph_im[l] + gi * ph_re[l];
        const double w = bin_rate * k;
        level[l] += re;
        first_moment[l] += w * re;
        curvature[l] += w * w * re;
        slope[l] += w * w * im * im;
      };
      if (count == kLanes) {
        for (int l = 0; l < kLanes; ++l) accumulate(l);
      } else {
        for (int l = 0; l < count; ++l) accumulate(l);
      }
      if (learn) {  // from the unweighted spectra: a bin weighted to zero must still learn
        for (int l = 0; l < count; ++l) {
          const int k = b + l;
          const CrossBin x = CrossAt(xr, xk, k);
          const double mag = std::sqrt(static_cast<double>(x.re) * x.re + static_cast<double>(x.im) * x.im);
          const double x_re = x.re * ph_re[l] - x.im * ph_im[l];
          const float aligned = mag > 0.0 ? static_cast<float>(x_re / mag) : 0.0f;
          average[k] += alpha * (aligned - average[k]);
        }
      }
      for (int l = 0; l < kLanes; ++l) {
        const double next_re = ph_re[l] * block_re - ph_im[l] * block_im;
        ph_im[l] = ph_re[l] * block_im + ph_im[l] * block_re;
        ph_re[l] = next_re;
      }
    }
  }
  for (int l = 0; l < kLanes; ++l) {
    stats.level += 2.0 * level[l];
    stats.first += 2.0 * first_moment[l];
    stats.curvature += 2.0 * curvature[l];
    stats.slope_var += 4.0 * slope[l];
  }
  // DC and Nyquist stand for one bin, not two: take back the excess (c_k = 1, c_k^2 = 1).
  for (int k : {0, n / 2}) {
    if (k < lo || k >= hi) continue;
    const double angle = step_angle * k;
    const double re = g[2 * k] * std::cos(angle) - g[2 * k + 1] * std::sin(angle);
    const double im = g[2 * k] * std::sin(angle) + g[2 * k + 1] * std::cos(angle);
    const double w = bin_rate * k;
    stats.level -= re;
    stats.first -= w * re;
    stats.curvature -= w * w * re;
    stats.slope_var -= 3.0 * w * w * im * im;
  }
  return stats;
}

// After a frame has been folded in: w = c^2 / (1 - c^2) from the bias-corrected average c
// (clamped to [0, 0.99]) for the pair's next frame.
void GccPhatEstimator::Impl::LearnCoherence(int pair) {
  const int frames = ++coherence_frames[pair];
  const double alpha = 1.0 / options.coherence_time_constant_frames;
  const double keep = 1.0 - alpha;
  // An average started at zero holds sum_w = 1 - keep^frames of the weight: divide it out.
  const double sum_w = 1.0 - std::pow(keep, frames);
  const double sum_w2 = alpha * alpha * (1.0 - std::pow(keep, 2 * frames)) / (1.0 - keep * keep);
  const int h = options.coherence_smoothing_bins;
  const int lo = layout.band_first_bin;
  const int hi = layout.band_end_bin;
  // A noise-only bin's aligned coherence is cos of a uniform phase: mean 0, variance 1/2. The
  // averaged, smoothed estimate then has variance v0 = (1/2) (sum_w2 / sum_w^2) / n_eff, n_eff
  // the independent bins in the 2h + 1 smoothed (zero padding correlates N / M neighbours):
  // c^2 is debiased by v0 so that noise-only bins get weight ~0 rather than ~v0.
  const double padding = static_cast<double>(layout.fft_size) / options.frame_samples;
  const double n_eff = std::max(1.0, (2.0 * h + 1.0) / padding);
  const float v0 = static_cast<float>(0.5 * sum_w2 / (sum_w * sum_w) / n_eff);
  const float correction = static_cast<float>(1.0 / sum_w);
  const std::size_t base = static_cast<std::size_t>(pair) * layout.bin_count;
  const float* average = coherence.data() + base;
  float* weight = coherence_weight.data() + base;
  // Box average over [k - h, k + h] within the band, by a running sum (double: no drift).
  double running = 0.0;
  int first = lo;
  int last = lo;  // the sum covers [first, last)
  float largest = 0.0f;
  for (int k = lo; k < hi; ++k) {
    while (last < std::min(hi, k + h + 1)) running += average[last++];
    while (first < k - h) running -= average[first++];
    const float c = std::max(0.0f, static_cast<float>(running / (last - first)) * correction);
    const float c2 = std::clamp(c * c - v0, 0.0f, 0.98f);
    weight[k] = c2 / (1.0f - c2);
    largest = std::max(largest, weight[k]);
  }
  coherence_usable[pair] = frames >= options.coherence_warmup_frames && largest > 1e-6f;
}

// Local extrema of R in the searched window (the padding either side gives the end samples
// a neighbour), the main peak first, then by decreasing |R|, each at least `radius` lags
// from those taken; each refined like the main peak (negative ones on -R).
void GccPhatEstimator::Impl::PickCandidates(std::span<const float> searched, int peak, int max_lag, double radius,
                                            double slope_std, PairMeasurement* out) {
  const int count = static_cast<int>(searched.size());
  const double fs = options.sample_rate_hz;
  const double cap = SigmaCapSamples(max_lag);
  const float* w = searched.data();  // w[-K .. count - 1 + K] are valid
  const auto sigma_of = [&](double curvature, double floor) {
    if (!(curvature < 0.0)) return cap;
    const double stat = slope_std / -curvature;
    return std::min(std::sqrt(stat * stat + floor * floor), cap);
  };
  extrema.clear();
  for (int i = 0; i < count; ++i) {
    if (i == peak) continue;
    const float v = w[i];
    const bool is_max = v > 0.0f && v > w[i - 1] && v >= w[i + 1];
    const bool is_min = v < 0.0f && v < w[i - 1] && v <= w[i + 1];
    if (is_max || is_min) extrema.push_back({std::abs(v), i});
  }
  std::sort(extrema.begin(), extrema.end(), [](const Extremum& a, const Extremum& b) {
    return a.magnitude != b.magnitude ? a.magnitude > b.magnitude : a.index < b.index;
  });
  out->candidates.resize(1);  // [0], the main peak, is filled by the caller
  std::array<int, kMaxCandidates> taken{};
  taken[0] = peak;
  int taken_count = 1;
  for (const Extremum& e : extrema) {
    if (taken_count >= options.max_candidates) break;
    bool clear = true;
    for (int t = 0; t < taken_count; ++t) clear = clear && std::abs(e.index - taken[t]) >= radius;
    if (!clear) continue;
    taken[taken_count++] = e.index;
    std::array<float, kPeakSamples> around{};
    const float sign = w[e.index] < 0.0f ? -1.0f : 1.0f;
    for (int m = 0; m < kPeakSamples; ++m) around[m] = sign * w[e.index - kPeakHalfWidth + m];
    const double offset = InterpolatePeak(options.interpolation, around);
    DelayCandidate candidate;
    candidate.delay_s = (e.index - max_lag + offset) / fs;
    candidate.value = w[e.index];
    candidate.delay_sigma_s =
        sigma_of(SincCurvature(around, offset), InterpolationErrorSamples(options.interpolation, around, offset)) / fs;
    out->candidates.push_back(candidate);
  }
}

void GccPhatEstimator::Impl::MeasurePair(int pair, PairMeasurement* out) {
  const int max_lag = layout.max_lag_samples[pair];
  const int searched_count = 2 * max_lag + 1;
  out->sensor = array.sensor_of_pair(pair);
  out->first_lag_samples = -max_lag;

  const float norm = WeighCrossSpectrum(pair);
  if (!(norm > 0.0f)) {  // no energy in the band: nothing to measure
    out->delay_s = 0.0;
    out->quality = 0.0;
    out->peak_value = 0.0;
    out->peak_snr = 0.0;
    out->delay_sigma_s = SigmaCapSamples(max_lag) / options.sample_rate_hz;
    out->candidates.clear();
    if (options.keep_gcc)
      out->gcc.assign(searched_count, 0.0f);
    else
      out->gcc.clear();
    return;
  }
  std::memcpy(weighed.get(), cross.get(), sizeof(float) * 2 * layout.bin_count);
  fftwf_execute(inverse.get());
  const float scale = 1.0f / norm;
  GatherWindow(max_lag, scale);

  const std::span<const float> searched(window.data() + kPeakHalfWidth, searched_count);
  const int peak = ArgMax(searched);
  const float peak_value = searched[peak];
  const std::span<const float, kPeakSamples> around(window.data() + peak, kPeakSamples);
  const double offset_samples = InterpolatePeak(options.interpolation, around);
  const int peak_lag = peak - max_lag;
  const double delay_samples = peak_lag + offset_samples;

  out->delay_s = delay_samples / options.sample_rate_hz;
  out->peak_value = peak_value;
  out->peak_snr = peak_value * layout.noise_floor_inverse;
  out->quality = QualityRatio(peak_value, LargestSidelobe(searched, peak, peak_lag, scale));

  // delay_sigma (gcc_phat.h): sigma = sqrt((N / M) sum c^2 w^2 Im^2) / sum c w^2 Re.
  const SpectrumStats stats = AnalyseSpectrum(pair, delay_samples);
  const double padding_factor = static_cast<double>(layout.fft_size) / static_cast<double>(options.frame_samples);
  const double slope_std = std::sqrt(padding_factor * stats.slope_var) / norm;  // std of R'
  const double floor = InterpolationErrorSamples(options.interpolation, around, offset_samples);
  const double cap = SigmaCapSamples(max_lag);
  double sigma = cap;
  if (stats.curvature > 0.0) {
    const double stat = slope_std / (stats.curvature / norm);
    sigma = std::min(std::sqrt(stat * stat + floor * floor), cap);
  }
  out->delay_sigma_s = sigma / options.sample_rate_hz;
  if (options.weighting == Weighting::kPhatCoherence) LearnCoherence(pair);

  // Candidates at least an envelope width apart: the rms width of the aligned spectrum.
  double radius = 1.0;
  if (stats.level > 0.0) {
    const double mean = stats.first / stats.level;
    const double var = stats.curvature / stats.level - mean * mean;
    if (var > 0.0)
      radius = std::clamp(kEnvelopeNullPerRmsWidth / std::sqrt(var), 1.0, static_cast<double>(searched_count));
  }
  if (options.max_candidates > 1) {
    PickCandidates(searched, peak, max_lag, radius, slope_std, out);
  } else {
    out->candidates.resize(1);  // the main peak alone: no scan of the window's extrema
  }
  out->candidates[0] = DelayCandidate{out->delay_s, out->peak_value, out->delay_sigma_s};

  if (options.keep_gcc)
    out->gcc.assign(searched.begin(), searched.end());
  else
    out->gcc.clear();
}

GccPhatEstimator::GccPhatEstimator(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
GccPhatEstimator::~GccPhatEstimator() = default;

StatusOr<std::unique_ptr<GccPhatEstimator>> GccPhatEstimator::Create(const ArrayGeometry& array,
                                                                     const GccOptions& options) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  auto impl = std::make_unique<Impl>(array, options);
  LOCALIZER_RETURN_IF_ERROR(impl->Init());
  return std::unique_ptr<GccPhatEstimator>(new GccPhatEstimator(std::move(impl)));
}

Status GccPhatEstimator::Estimate(const float* frame, int frame_samples, double t_s, Measurement* out) {
  Impl& s = *impl_;
  if (frame == nullptr) return InvalidArgument("frame is null");
  if (out == nullptr) return InvalidArgument("out (the Measurement to fill) is null");
  if (frame_samples != s.options.frame_samples) {
    return InvalidArgument(
        "frame_samples is " + std::to_string(frame_samples) +
        "; the estimator was created for frame_samples = " + std::to_string(s.options.frame_samples));
  }
  for (int ch = 0; ch < s.array.sensor_count(); ++ch) {
    LOCALIZER_RETURN_IF_ERROR(s.TransformChannel(frame + static_cast<std::size_t>(ch) * frame_samples, ch));
  }
  out->t_s = t_s;
  out->sample_rate_hz = s.options.sample_rate_hz;
  out->pairs.resize(s.array.pair_count());
  for (int p = 0; p < s.array.pair_count(); ++p) s.MeasurePair(p, &out->pairs[p]);
  return Status::Ok();
}

void GccPhatEstimator::Reset() {
  Impl& s = *impl_;
  std::fill(s.coherence.begin(), s.coherence.end(), 0.0f);
  std::fill(s.coherence_weight.begin(), s.coherence_weight.end(), 0.0f);
  std::fill(s.coherence_frames.begin(), s.coherence_frames.end(), 0);
  std::fill(s.coherence_usable.begin(), s.coherence_usable.end(), 0);
}

const GccOptions& GccPhatEstimator::options() const { return impl_->options; }
int GccPhatEstimator::fft_size() const { return impl_->layout.fft_size; }
int GccPhatEstimator::max_lag_samples(int pair) const { return impl_->layout.max_lag_samples[pair]; }

}  // namespace localizer::engine
