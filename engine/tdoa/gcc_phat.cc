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
#include "engine/tdoa/delay_warp.h"
#include "engine/tdoa/fftw_util.h"
#include "engine/tdoa/gcc_layout.h"
#include "engine/tdoa/gcc_phat_impl.h"

namespace localizer::engine {
namespace {

// SetDelayRates' bound: 2 v / c for 8.6 m/s in air or 37 m/s in water, beyond what a
// tracked acoustic source does; a larger rate is a caller's error.
constexpr double kMaxDelayRate = 0.05;

// Copies one channel into the zero-padded transform input, times the frame's taper when
// `window` holds its n gains (gcc_math.h's TaperGain; empty: a plain copy), and returns the
// copy's energy (sum of squares, double so that no finite input overflows). One pass; partial
// sums in kLanes lanes let the compiler vectorise the reduction without reassociating a
// single float sum.
double CopyChannel(const float* src, int n, std::span<const float> window, float* dst) {
  const bool windowed = !window.empty();
  double lanes[kLanes] = {};
  int i = 0;
  for (; i + kLanes <= n; i += kLanes) {
    for (int j = 0; j < kLanes; ++j) {
      const float v = windowed ? src[i + j] * window[static_cast<std::size_t>(i + j)] : src[i + j];
      dst[i + j] = v;
      lanes[j] += static_cast<double>(v) * v;
    }
  }
  double energy = 0.0;
  for (; i < n; ++i) {
    const float v = windowed ? src[i] * window[static_cast<std::size_t>(i)] : src[i];
    dst[i] = v;
    energy += static_cast<double>(v) * v;
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

// ---- Estimator ----------------------------------------------------------------------------

Status GccPhatEstimator::Impl::Init() {
  auto computed = ComputeGccLayout(array, options);
  if (!computed.ok()) return computed.status();
  layout = std::move(computed).value();
  taper_gains = TaperGains(options.frame_samples, options.taper_fraction);
  warped.assign(options.frame_samples, 0.0f);
  const int fft_size = layout.fft_size;
  spectrum_stride = (2 * layout.bin_count + 15) / 16 * 16;
  kept_spectrum.assign(spectrum_stride, 0.0f);
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
  const double e = CopyChannel(samples, options.frame_samples, taper_gains, padded.get());
  if (!std::isfinite(e)) {
    return InvalidArgument("channel " + std::to_string(channel) + " holds a non-finite sample (NaN or Inf)");
  }
  energy[channel] = e;
  float* spectrum = spectra.get() + static_cast<std::size_t>(channel) * spectrum_stride;
  fftwf_execute_dft_r2c(forward.get(), padded.get(), AsComplex(spectrum));
  return Status::Ok();
}

void GccPhatEstimator::Impl::MeasureWarpedPairs(const float* frame, Measurement* out) {
  // kPhatCoherence learns from every measured pair: measuring one twice would count it twice.
  if (options.weighting == Weighting::kPhatCoherence) return;
  const int n = options.frame_samples;
  for (int p = 0; p < array.pair_count(); ++p) {
    const int sensor = array.sensor_of_pair(p);
    const double rate = sensor_rate[sensor];
    if (rate == 0.0) continue;
    float* spectrum = spectra.get() + static_cast<std::size_t>(sensor) * spectrum_stride;
    std::memcpy(kept_spectrum.data(), spectrum, sizeof(float) * spectrum_stride);
    const double kept_energy = energy[sensor];
    WarpChannel(frame + static_cast<std::size_t>(sensor) * n, n, rate, warped.data());
    if (TransformChannel(warped.data(), sensor).ok()) {  // finite: the plain channel was
      MeasurePair(p, &warped_pair);
      if (warped_pair.peak_value > out->pairs[p].peak_value) {
        std::swap(out->pairs[p], warped_pair);
        continue;
      }
    }
    std::memcpy(spectrum, kept_spectrum.data(), sizeof(float) * spectrum_stride);
    energy[sensor] = kept_energy;
  }
}

float GccPhatEstimator::Impl::WeighCrossSpectrum(int pair) {
  return WeighSensors(array.reference_sensor(), array.sensor_of_pair(pair), pair);
}

// Fills `cross` with G = W X_k conj(X_r) B for sensors r = ref, k = sensor and returns S, the
// sum of |G| over all N bins. `pair` picks kPhatCoherence's learnt weights (-1: plain PHAT).
float GccPhatEstimator::Impl::WeighSensors(int ref, int sensor, int pair) {
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
      if (pair >= 0 && coherence_usable[pair]) {
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

// Noise alone gives each bin a uniform phase, so R(l) = (1/S) sum_k G_k e^{j w_k l} has
// variance (sum over interior bins of 2 |G_k|^2 + |G_0|^2 + |G_N/2|^2) / S^2: 1 / (2 B) for
// PHAT's B unit bins (the layout's constant), 1 / (2 B_eff) with B_eff = (sum w)^2 / sum w^2
// for learnt weights, which gather on a few bins and would otherwise read noise as a source
// many times over. Reads the kept cross-spectrum `weighed`.
float GccPhatEstimator::Impl::WeighedNoiseFloorInverse(float norm) const {
  const float* g = weighed.get();
  const int lo = layout.band_first_bin;
  const int hi = layout.band_end_bin;
  const int last = layout.bin_count - 1;
  // Sum of squares over the band's interleaved floats, in independent lanes so it vectorises;
  // then DC and Nyquist (whose imaginary parts are 0) counted once.
  double lanes[kLanes] = {};
  const float* first = g + 2 * lo;
  const int count = 2 * (hi - lo);
  int i = 0;
  for (; i + kLanes <= count; i += kLanes) {
    for (int l = 0; l < kLanes; ++l) lanes[l] += static_cast<double>(first[i + l]) * first[i + l];
  }
  double power = 0.0;
  for (; i < count; ++i) power += static_cast<double>(first[i]) * first[i];
  for (double lane : lanes) power += lane;
  double variance = 2.0 * power;
  if (lo == 0) variance -= static_cast<double>(g[0]) * g[0];
  if (hi == last + 1) variance -= static_cast<double>(g[2 * last]) * g[2 * last];
  return variance > 0.0 ? layout.taper_noise_factor * static_cast<float>(norm / std::sqrt(variance)) : 0.0f;
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
  const bool learnt = options.weighting == Weighting::kPhatCoherence && coherence_usable[pair];
  const float noise_floor_inverse = learnt ? WeighedNoiseFloorInverse(norm) : layout.noise_floor_inverse;
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
  out->peak_snr = peak_value * noise_floor_inverse;
  out->quality = QualityRatio(peak_value, LargestSidelobe(searched, peak, peak_lag, scale));

  const double padding_factor = static_cast<double>(layout.fft_size) / static_cast<double>(options.frame_samples);
  const DelaySpread spread =
      SpreadFromMoments(AnalyseSpectrum(pair, delay_samples), norm, padding_factor,
                        InterpolationErrorSamples(options.interpolation, around, offset_samples), max_lag);
  out->delay_sigma_s = spread.sigma_samples / options.sample_rate_hz;
  if (options.weighting == Weighting::kPhatCoherence) LearnCoherence(pair);
  PickDelayCandidates(searched, peak, max_lag, spread, options.interpolation, options.sample_rate_hz,
                      options.max_candidates, &extrema, out);

  if (options.keep_gcc)
    out->gcc.assign(searched.begin(), searched.end());
  else
    out->gcc.clear();
}

void GccPhatEstimator::Impl::MeasureCrossPair(int index, CrossPairGcc* out) {
  const auto [a, b] = layout.cross_sensors[static_cast<std::size_t>(index)];
  const int max_lag = layout.cross_max_lag_samples[static_cast<std::size_t>(index)];
  out->sensor_a = a;
  out->sensor_b = b;
  out->first_lag_samples = -max_lag;
  const float norm = WeighSensors(a, b, /*pair=*/-1);
  if (!(norm > 0.0f)) {
    out->noise_floor_inverse = 0.0;
    out->gcc.assign(2 * max_lag + 1, 0.0f);
    return;
  }
  out->noise_floor_inverse = layout.noise_floor_inverse;
  fftwf_execute(inverse.get());
  GatherWindow(max_lag, 1.0f / norm);
  const float* searched = window.data() + kPeakHalfWidth;
  out->gcc.assign(searched, searched + 2 * max_lag + 1);
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
  s.have_spectra = false;
  for (int ch = 0; ch < s.array.sensor_count(); ++ch) {
    LOCALIZER_RETURN_IF_ERROR(s.TransformChannel(frame + static_cast<std::size_t>(ch) * frame_samples, ch));
  }
  out->t_s = t_s;
  out->sample_rate_hz = s.options.sample_rate_hz;
  out->pairs.resize(s.array.pair_count());
  for (int p = 0; p < s.array.pair_count(); ++p) s.MeasurePair(p, &out->pairs[p]);
  if (!s.sensor_rate.empty()) s.MeasureWarpedPairs(frame, out);
  out->cross_pairs.clear();  // measured on request, from these spectra (MeasureCrossPairs)
  s.have_spectra = true;
  return Status::Ok();
}

Status GccPhatEstimator::MeasureCrossPairs(Measurement* out) {
  Impl& s = *impl_;
  if (out == nullptr) return InvalidArgument("out (the Measurement to fill) is null");
  if (!s.have_spectra) return FailedPrecondition("MeasureCrossPairs needs a frame estimated first");
  out->cross_pairs.resize(s.layout.cross_sensors.size());
  for (std::size_t q = 0; q < out->cross_pairs.size(); ++q)
    s.MeasureCrossPair(static_cast<int>(q), &out->cross_pairs[q]);
  return Status::Ok();
}

Status GccPhatEstimator::SetDelayRates(std::span<const double> rate_per_pair) {
  Impl& s = *impl_;
  if (rate_per_pair.empty()) {
    s.sensor_rate.clear();
    return Status::Ok();
  }
  if (static_cast<int>(rate_per_pair.size()) != s.array.pair_count()) {
    return InvalidArgument("delay rates: " + std::to_string(rate_per_pair.size()) + " given for " +
                           std::to_string(s.array.pair_count()) + " pairs");
  }
  for (std::size_t p = 0; p < rate_per_pair.size(); ++p) {
    if (!(std::abs(rate_per_pair[p]) < kMaxDelayRate)) {
      return InvalidArgument("delay rate of pair " + std::to_string(p) + " is " + std::to_string(rate_per_pair[p]) +
                             "; must be finite with magnitude below 0.05");
    }
  }
  s.sensor_rate.assign(s.array.sensor_count(), 0.0);
  for (int p = 0; p < s.array.pair_count(); ++p) s.sensor_rate[s.array.sensor_of_pair(p)] = rate_per_pair[p];
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
