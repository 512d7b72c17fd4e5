#include "engine/sim/source_signal.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "engine/sim/band_pass_fir.h"
#include "engine/sim/seeding.h"

namespace localizer::engine {
namespace {

constexpr int64_t kNoiseBlock = 4096;         // grid samples drawn from one engine
constexpr double kClickJitterFraction = 0.2;  // of the click period, each way

int64_t FloorDiv(int64_t a, int64_t b) {
  const int64_t q = a / b;
  return (a % b != 0 && (a < 0) != (b < 0)) ? q - 1 : q;
}

// Unit white Gaussian noise at grid indices [first, first + count), index 0 at emission time
// 0. Each block of kNoiseBlock indices has its own engine, so a value depends on its index
// only.
std::vector<double> WhiteNoise(uint64_t seed, int64_t first, int64_t count) {
  std::vector<double> out(count);
  std::vector<double> block(kNoiseBlock);
  const int64_t end = first + count;
  for (int64_t i = first; i < end;) {
    const int64_t block_index = FloorDiv(i, kNoiseBlock);
    std::mt19937_64 engine = SeededEngine(seed, RandomStream::kSourceNoise, block_index);
    std::normal_distribution<double> normal;
    for (double& v : block) v = normal(engine);
    const int64_t block_start = block_index * kNoiseBlock;
    const int64_t stop = std::min(end, block_start + kNoiseBlock);
    for (; i < stop; ++i) out[i - first] = block[i - block_start];
  }
  return out;
}

std::vector<double> BroadbandSamples(const SimOptions& options, int64_t first, int64_t count) {
  const BandPassFir fir = DesignBandPassFir(options.band_low_hz, options.band_high_hz, options.sample_rate_hz);
  const auto half = static_cast<int64_t>(fir.taps.size() - 1) / 2;
  // Draw `half` extra samples each side so every output sample sees a full filter.
  std::vector<double> filtered = FilterValid(WhiteNoise(options.seed, first - half, count + 2 * half), fir.taps);
  double noise_gain = 0.0;
  for (double h : fir.taps) noise_gain += h * h;
  const double scale = 1.0 / std::sqrt(noise_gain);
  for (double& v : filtered) v *= scale;
  return filtered;
}

// Adds every click whose pulse overlaps the grid; returns the click times it used.
std::vector<double> AddClicks(const SimOptions& options, int64_t first, std::vector<double>& samples) {
  const ClickPulse pulse(options.band_low_hz, options.band_high_hz);
  const double fs = options.sample_rate_hz;
  const double half_s = 0.5 * pulse.duration_s();
  const auto count = static_cast<int64_t>(samples.size());
  const double start_s = static_cast<double>(first) / fs;
  const double end_s = static_cast<double>(first + count - 1) / fs;
  std::vector<double> times = ClickEmissionTimes(options, start_s - half_s, end_s + half_s);
  for (double t_click_s : times) {
    const auto lo = std::max<int64_t>(static_cast<int64_t>(std::ceil((t_click_s - half_s) * fs)), first);
    const auto hi = std::min<int64_t>(static_cast<int64_t>(std::floor((t_click_s + half_s) * fs)), first + count - 1);
    for (int64_t n = lo; n <= hi; ++n) {
      samples[n - first] += pulse(static_cast<double>(n) / fs - t_click_s);
    }
  }
  return times;
}

}  // namespace

ClickPulse::ClickPulse(double band_low_hz, double band_high_hz)
    : centre_hz_(0.5 * (band_low_hz + band_high_hz)), duration_s_(6.0 / (band_high_hz - band_low_hz)) {}

double ClickPulse::operator()(double t_s) const {
  const double u = t_s / duration_s_;  // window coordinate, [-1/2, 1/2] inside the pulse
  if (std::abs(u) >= 0.5) return 0.0;
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  const double blackman = 0.42 + 0.5 * std::cos(kTwoPi * u) + 0.08 * std::cos(2.0 * kTwoPi * u);
  return blackman * std::cos(kTwoPi * centre_hz_ * t_s);
}

std::vector<double> ClickEmissionTimes(const SimOptions& options, double start_s, double end_s) {
  const double rate_hz = options.click_rate_hz;
  std::vector<double> times;
  // Jitter moves a click by less than a period, so one extra nominal slot each side suffices.
  const auto k_first = static_cast<int64_t>(std::floor(start_s * rate_hz)) - 1;
  const auto k_last = static_cast<int64_t>(std::ceil(end_s * rate_hz)) + 1;
  for (int64_t k = k_first; k <= k_last; ++k) {
    std::mt19937_64 engine = SeededEngine(options.seed, RandomStream::kClickJitter, k);
    std::uniform_real_distribution<double> jitter(-kClickJitterFraction, kClickJitterFraction);
    const double t_s = (static_cast<double>(k) + jitter(engine)) / rate_hz;
    if (t_s >= start_s && t_s <= end_s) times.push_back(t_s);
  }
  return times;
}

std::vector<Tone> SourceTones(const SimOptions& options) {
  std::vector<Tone> tones;
  if (options.signal != SourceSignal::kTonalBroadband) return tones;
  std::mt19937_64 engine = SeededEngine(options.seed, RandomStream::kTones, 0);
  const double width_hz = options.band_high_hz - options.band_low_hz;
  std::uniform_real_distribution<double> frequency(options.band_low_hz + 0.1 * width_hz,
                                                   options.band_high_hz - 0.1 * width_hz);
  std::uniform_real_distribution<double> phase(0.0, 2.0 * std::numbers::pi);
  const double amplitude = std::sqrt(2.0 * options.tone_power_fraction / static_cast<double>(options.tone_count));
  for (int i = 0; i < options.tone_count; ++i) {
    Tone tone;
    tone.frequency_hz = frequency(engine);
    tone.phase_rad = phase(engine);
    tone.amplitude = amplitude;
    tones.push_back(tone);
  }
  return tones;
}

SourceWaveform MakeSourceWaveform(const SimOptions& options, double start_s, double end_s) {
  SourceWaveform out;
  out.sample_rate_hz = options.sample_rate_hz;
  const auto first = static_cast<int64_t>(std::floor(start_s * options.sample_rate_hz));
  const auto last = static_cast<int64_t>(std::ceil(end_s * options.sample_rate_hz));
  const int64_t count = last - first + 1;
  out.origin_index = -first;
  if (options.signal == SourceSignal::kBroadband) {
    out.samples = BroadbandSamples(options, first, count);
  } else if (options.signal == SourceSignal::kTonalBroadband) {
    out.samples = BroadbandSamples(options, first, count);
    const double noise_gain = std::sqrt(1.0 - options.tone_power_fraction);
    const std::vector<Tone> tones = SourceTones(options);
    for (int64_t i = 0; i < count; ++i) {
      const double t_s = static_cast<double>(first + i) / options.sample_rate_hz;
      double v = noise_gain * out.samples[i];
      for (const Tone& tone : tones) {
        v += tone.amplitude * std::cos(2.0 * std::numbers::pi * tone.frequency_hz * t_s + tone.phase_rad);
      }
      out.samples[i] = v;
    }
  } else {
    out.samples.assign(count, 0.0);
    out.click_times_s = AddClicks(options, first, out.samples);
  }
  return out;
}

}  // namespace localizer::engine
