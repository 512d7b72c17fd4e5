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
#include <utility>
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

// kPhatShare's floor: each bin's power averaged over 33 bins (a 4096-sample frame has 2049;
// the direction search's 512-sample frames read 9), so that a source a few dB over the noise
// over a quarter of the band is not read as a flat frame (signal_share.h).
constexpr std::size_t kShareFloorWindowBins = 32;

// Copies channels a and b into the zero-padded transform input, interleaved (a(i) at dst[2i],
// b(i) at dst[2i + 1]: packed_transforms.h's real and imaginary parts; b null: zeros), each
// times the frame's taper when `window` holds its n gains (gcc_math.h's TaperGain; empty: a
// plain copy), and returns the copies' energies (sums of squares, double so that no finite
// input overflows). One pass; partial sums in kLanes lanes let the compiler vectorise the
// reductions without reassociating a single float sum.
std::pair<double, double> CopyChannels(const float* a, const float* b, int n, std::span<const float> window,
                                       float* dst) {
  const bool windowed = !window.empty();
  const auto tapered = [&](const float* src, int i) {
    return windowed ? src[i] * window[static_cast<std::size_t>(i)] : src[i];
  };
  double lanes_a[kLanes] = {}, lanes_b[kLanes] = {};
  int i = 0;
  for (; i + kLanes <= n; i += kLanes) {
    for (int j = 0; j < kLanes; ++j) {
      const float va = tapered(a, i + j);
      const float vb = b != nullptr ? tapered(b, i + j) : 0.0f;
      dst[2 * (i + j)] = va;
      dst[2 * (i + j) + 1] = vb;
      lanes_a[j] += static_cast<double>(va) * va;
      lanes_b[j] += static_cast<double>(vb) * vb;
    }
  }
  double energy_a = 0.0, energy_b = 0.0;
  for (; i < n; ++i) {
    const float va = tapered(a, i);
    const float vb = b != nullptr ? tapered(b, i) : 0.0f;
    dst[2 * i] = va;
    dst[2 * i + 1] = vb;
    energy_a += static_cast<double>(va) * va;
    energy_b += static_cast<double>(vb) * vb;
  }
  for (double lane : lanes_a) energy_a += lane;
  for (double lane : lanes_b) energy_b += lane;
  return {energy_a, energy_b};
}

int ArgMax(std::span<const float> r) { return static_cast<int>(std::max_element(r.begin(), r.end()) - r.begin()); }

float MaxAbs(std::span<const float> r) {
  float best = 0.0f;
  for (float v : r) best = std::max(best, std::abs(v));
  return best;
}

// The fallback for a window that is all main lobe: the same lobe rule on the full circular
// correlation of length n (gcc_math.h; lag l at corr[2 (l mod n)]), and the largest |R|
// outside it.
float LargestOutsideLobe(const float* corr, int n, int peak_lag) {
  const auto at = [&](int lag) { return corr[2 * WrapLag(lag, n)]; };
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
  share_finder = SignalShare(SignalShareOptionsForNoise(array.sensor_count(), kShareFloorWindowBins));
  if (options.weighting == Weighting::kPhatShare) share_weight.assign(layout.bin_count, 0.0f);  // 0 out of band

  // One more channel slot than sensors: the partner of a channel transformed alone.
  spectra = AllocateFftwFloats(static_cast<std::size_t>(spectrum_stride) * (array.sensor_count() + 1));
  cross = AllocateFftwFloats(2 * layout.bin_count);
  cross_b = AllocateFftwFloats(2 * layout.bin_count);
  if (options.weighting == Weighting::kPhatCoherence) {
    const std::size_t cells = static_cast<std::size_t>(array.pair_count()) * layout.bin_count;
    coherence.assign(cells, 0.0f);
    coherence_weight.assign(cells, 0.0f);
    coherence_frames.assign(array.pair_count(), 0);
    coherence_usable.assign(array.pair_count(), 0);
  }
  extrema.reserve(2 * widest_lag + 1);
  const unsigned flags = options.measure_fft_plans ? FFTW_MEASURE : FFTW_ESTIMATE;
  // kPhatShare reads its floor from every bin (gcc_weighing.cc, FindShares), so every bin is
  // unpacked; the bins out of band stay unweighed (zero) in what the inverse reads.
  const bool every_bin = options.weighting == Weighting::kPhatShare;
  if (!packed.Init(fft_size, every_bin ? 0 : layout.band_first_bin, every_bin ? layout.bin_count : layout.band_end_bin,
                   flags)) {
    return Internal("FFTW could not plan complex transforms of size " + std::to_string(fft_size));
  }
  return Status::Ok();
}

float* GccPhatEstimator::Impl::SpectrumOf(int channel) {
  return spectra.get() + static_cast<std::size_t>(channel) * spectrum_stride;
}

// Channels a and b (b < 0: a alone) through one packed forward transform into their slots in
// `spectra`. The padded tail stays zero: the transform preserves its input, and only the
// first frame_samples of each part are ever written.
Status GccPhatEstimator::Impl::TransformChannels(const float* samples_a, int a, const float* samples_b, int b) {
  const auto [e_a, e_b] =
      CopyChannels(samples_a, b >= 0 ? samples_b : nullptr, options.frame_samples, taper_gains, packed.forward_input());
  for (const auto& [e, channel] : {std::pair{e_a, a}, std::pair{e_b, b}}) {
    if (!std::isfinite(e)) {
      return InvalidArgument("channel " + std::to_string(channel) + " holds a non-finite sample (NaN or Inf)");
    }
  }
  energy[a] = e_a;
  if (b >= 0) energy[b] = e_b;
  packed.Forward(SpectrumOf(a), SpectrumOf(b >= 0 ? b : array.sensor_count()));
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
    float* spectrum = SpectrumOf(sensor);
    std::memcpy(kept_spectrum.data(), spectrum, sizeof(float) * spectrum_stride);
    const double kept_energy = energy[sensor];
    WarpChannel(frame + static_cast<std::size_t>(sensor) * n, n, rate, warped.data());
    if (TransformChannels(warped.data(), sensor, nullptr, -1).ok()) {  // finite: the plain channel was
      MeasureOnePair(p, &warped_pair);
      if (warped_pair.peak_value > out->pairs[p].peak_value) {
        std::swap(out->pairs[p], warped_pair);
        continue;
      }
    }
    std::memcpy(spectrum, kept_spectrum.data(), sizeof(float) * spectrum_stride);
    energy[sensor] = kept_energy;
  }
}

// window[i] = R(i - L - K) * scale: the searched lags plus kPeakHalfWidth either side for
// the interpolator. Lags wrap modulo N; L + K < N keeps both runs inside the correlation
// (lag l at corr[2 (l mod N)]: packed_transforms.h's output).
void GccPhatEstimator::Impl::GatherWindow(const float* corr, int max_lag, float scale) {
  const int reach = max_lag + kPeakHalfWidth;
  const float* negative = corr + 2 * (layout.fft_size - reach);  // lags -reach .. -1
  float* w = window.data();
  for (int i = 0; i < reach; ++i) w[i] = negative[2 * i] * scale;
  for (int i = 0; i <= reach; ++i) w[reach + i] = corr[2 * i] * scale;  // lags 0 .. reach
}

// Largest |R| outside the main lobe within the window, or, when the lobe fills the window,
// outside it in the whole correlation (scaled like the window).
float GccPhatEstimator::Impl::LargestSidelobe(const float* corr, std::span<const float> searched, int peak,
                                              int peak_lag, float scale) const {
  int first, last;
  MainLobe([&](int i) { return searched[i]; }, static_cast<int>(searched.size()), peak, &first, &last);
  if (first > 0 || last + 1 < static_cast<int>(searched.size())) {
    return std::max(MaxAbs(searched.first(first)), MaxAbs(searched.subspan(last + 1)));
  }
  return scale * LargestOutsideLobe(corr, layout.fft_size, peak_lag);
}

void GccPhatEstimator::Impl::MeasureWithoutEnergy(int pair, PairMeasurement* out) const {
  const int max_lag = layout.max_lag_samples[pair];
  out->sensor = array.sensor_of_pair(pair);
  out->first_lag_samples = -max_lag;
  out->delay_s = 0.0;
  out->quality = 0.0;
  out->peak_value = 0.0;
  out->peak_snr = 0.0;
  out->delay_sigma_s = SigmaCapSamples(max_lag) / options.sample_rate_hz;
  out->candidates.clear();
  if (options.keep_gcc)
    out->gcc.assign(2 * max_lag + 1, 0.0f);
  else
    out->gcc.clear();
}

float GccPhatEstimator::Impl::WeighItem(int item, float* g) {
  const int pairs = array.pair_count();
  if (item < pairs) return WeighCrossSpectrum(item, g);
  const auto [a, b] = layout.cross_sensors[static_cast<std::size_t>(item - pairs)];
  return WeighSensors(a, b, /*pair=*/-1, g);
}

void GccPhatEstimator::Impl::ReadItem(int item, float norm, const float* g, const float* corr, Measurement* out) {
  const int pairs = array.pair_count();
  if (item >= pairs) {
    ReadCrossPair(item - pairs, norm, g, corr, &out->cross_pairs[static_cast<std::size_t>(item - pairs)]);
  } else if (norm > 0.0f) {
    ReadPair(item, norm, g, corr, &out->pairs[static_cast<std::size_t>(item)]);
  } else {  // no energy in the band: nothing to measure
    MeasureWithoutEnergy(item, &out->pairs[static_cast<std::size_t>(item)]);
  }
}

void GccPhatEstimator::Impl::MeasureItems(int first, int end, Measurement* out) {
  for (int a = first; a < end; a += 2) {
    const int b = a + 1 < end ? a + 1 : -1;
    const float norm_a = WeighItem(a, cross.get());
    const float norm_b = b >= 0 ? WeighItem(b, cross_b.get()) : 0.0f;
    const bool heard_a = norm_a > 0.0f;
    const bool heard_b = norm_b > 0.0f;
    if (heard_a || heard_b) packed.Inverse(heard_a ? cross.get() : nullptr, heard_b ? cross_b.get() : nullptr);
    const float* corr = packed.inverse_output();
    ReadItem(a, norm_a, cross.get(), corr, out);  // a norm not above 0 reads as no energy
    if (b >= 0) ReadItem(b, norm_b, cross_b.get(), corr + 1, out);
  }
}

void GccPhatEstimator::Impl::MeasureOnePair(int pair, PairMeasurement* out) {
  const float norm = WeighCrossSpectrum(pair, cross.get());
  if (!(norm > 0.0f)) {
    MeasureWithoutEnergy(pair, out);
    return;
  }
  packed.Inverse(cross.get(), nullptr);
  ReadPair(pair, norm, cross.get(), packed.inverse_output(), out);
}

void GccPhatEstimator::Impl::ReadPair(int pair, float norm, const float* g, const float* corr, PairMeasurement* out) {
  const int max_lag = layout.max_lag_samples[pair];
  const int searched_count = 2 * max_lag + 1;
  out->sensor = array.sensor_of_pair(pair);
  out->first_lag_samples = -max_lag;
  const float noise_floor_inverse =
      WeighedBeyondPhat(pair) ? WeighedNoiseFloorInverse(norm, g) : layout.noise_floor_inverse;
  const float scale = 1.0f / norm;
  GatherWindow(corr, max_lag, scale);

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
  out->quality = QualityRatio(peak_value, LargestSidelobe(corr, searched, peak, peak_lag, scale));

  const double padding_factor = static_cast<double>(layout.fft_size) / static_cast<double>(options.frame_samples);
  const DelaySpread spread =
      SpreadFromMoments(AnalyseSpectrum(pair, delay_samples, g), norm, padding_factor,
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

void GccPhatEstimator::Impl::ReadCrossPair(int index, float norm, const float* g, const float* corr,
                                           CrossPairGcc* out) {
  const auto [a, b] = layout.cross_sensors[static_cast<std::size_t>(index)];
  const int max_lag = layout.cross_max_lag_samples[static_cast<std::size_t>(index)];
  out->sensor_a = a;
  out->sensor_b = b;
  out->first_lag_samples = -max_lag;
  if (!(norm > 0.0f)) {
    out->noise_floor_inverse = 0.0;
    out->gcc.assign(2 * max_lag + 1, 0.0f);
    out->gcc_beyond.assign(2 * kPeakHalfWidth, 0.0f);
    return;
  }
  out->noise_floor_inverse = WeighedBeyondPhat(-1) ? WeighedNoiseFloorInverse(norm, g) : layout.noise_floor_inverse;
  GatherWindow(corr, max_lag, 1.0f / norm);
  const float* searched = window.data() + kPeakHalfWidth;
  out->gcc.assign(searched, searched + 2 * max_lag + 1);
  out->gcc_beyond.assign(window.data(), window.data() + kPeakHalfWidth);
  out->gcc_beyond.insert(out->gcc_beyond.end(), searched + 2 * max_lag + 1,
                         searched + 2 * max_lag + 1 + kPeakHalfWidth);
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
  const int sensors = s.array.sensor_count();
  const auto channel = [&](int ch) { return frame + static_cast<std::size_t>(ch) * frame_samples; };
  for (int ch = 0; ch < sensors; ch += 2) {
    const int partner = ch + 1 < sensors ? ch + 1 : -1;
    LOCALIZER_RETURN_IF_ERROR(s.TransformChannels(channel(ch), ch, partner >= 0 ? channel(partner) : nullptr, partner));
  }
  if (s.options.weighting == Weighting::kPhatShare) s.FindShares();
  out->t_s = t_s;
  out->sample_rate_hz = s.options.sample_rate_hz;
  out->window_time_var_s2 = s.layout.window_time_var_s2;
  const int pairs = s.array.pair_count();
  out->pairs.resize(pairs);
  // The cross pairs along with the frame's when asked for, unless warped readings may still
  // replace a channel's spectrum (they are measured from the kept readings').
  const bool with_cross = s.options.cross_pairs_with_frame && s.sensor_rate.empty();
  out->cross_pairs.resize(with_cross ? s.layout.cross_sensors.size() : 0);
  s.MeasureItems(0, pairs + static_cast<int>(out->cross_pairs.size()), out);
  if (!s.sensor_rate.empty()) s.MeasureWarpedPairs(frame, out);
  s.have_spectra = true;
  return Status::Ok();
}

Status GccPhatEstimator::MeasureCrossPairs(Measurement* out) {
  Impl& s = *impl_;
  if (out == nullptr) return InvalidArgument("out (the Measurement to fill) is null");
  if (!s.have_spectra) return FailedPrecondition("MeasureCrossPairs needs a frame estimated first");
  const int count = static_cast<int>(s.layout.cross_sensors.size());
  out->cross_pairs.resize(count);
  const int pairs = s.array.pair_count();
  s.MeasureItems(pairs, pairs + count, out);
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
