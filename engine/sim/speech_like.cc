#include "engine/sim/speech_like.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "engine/sim/band_pass_fir.h"

namespace localizer::engine {
namespace {

constexpr double kEdge_s = 0.01;
constexpr double kVoicedShare = 0.7;
constexpr double kTwoPi = 2.0 * std::numbers::pi;
// Voiced harmonics stop here (the unvoiced hiss covers the band above): it bounds the work per
// sample at about 100 harmonics whatever the rate.
constexpr double kMaxHarmonic_hz = 8000.0;

// A formant's bump added to the tilt's 1: prominence at its centre, half of that at +-width / 2.
double Formant(double f, double centre_hz, double width_hz, double prominence) {
  const double x = (f - centre_hz) / (0.5 * width_hz);
  return prominence / (1.0 + x * x);
}

}  // namespace

std::vector<double> SpeechLikeSignal(double band_low_hz, double band_high_hz, double fs, int64_t n,
                                     std::mt19937_64* rng) {
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const auto draw = [&](double a, double b) { return a + (b - a) * uniform(*rng); };
  const double f0_hz = draw(90.0, 250.0);
  const std::vector<double> hiss =
      UnitPowerBandNoise(std::max(band_low_hz, 0.3 * band_high_hz), band_high_hz, fs, n, rng);
  std::vector<double> out(static_cast<size_t>(n), 0.0);
  double t_s = -draw(0.0, 0.25);  // a random phase
  const double end_s = static_cast<double>(n) / fs;
  while (t_s < end_s) {
    const double length_s = draw(0.12, 0.25);
    const double gain = std::pow(10.0, draw(-6.0, 6.0) / 20.0);
    const bool voiced = uniform(*rng) < kVoicedShare;
    const double f_start = f0_hz * draw(0.85, 1.15), f_end = f0_hz * draw(0.85, 1.15);
    const double formants[3] = {draw(300.0, 800.0), draw(900.0, 2300.0), draw(2300.0, 3200.0)};
    const double widths[3] = {draw(100.0, 250.0), draw(100.0, 250.0), draw(100.0, 250.0)};
    // Harmonic amplitudes at the syllable's mean fundamental: -6 dB per octave, times the
    // formants' bumps (20, 16 and 10 dB above the tilt at their centres).
    std::vector<double> amplitude, phase;
    const double f_mean = 0.5 * (f_start + f_end);
    for (int k = 1; k * f_mean <= std::min(band_high_hz, kMaxHarmonic_hz); ++k) {
      const double f = k * f_mean;
      const double shape = 1.0 + Formant(f, formants[0], widths[0], 9.0) + Formant(f, formants[1], widths[1], 5.3) +
                           Formant(f, formants[2], widths[2], 2.2);
      amplitude.push_back(f >= band_low_hz ? shape / k : 0.0);
      phase.push_back(kTwoPi * uniform(*rng));
    }
    const auto first = std::max<int64_t>(0, static_cast<int64_t>(std::ceil(t_s * fs)));
    const auto last = std::min<int64_t>(n, static_cast<int64_t>(std::ceil((t_s + length_s) * fs)));
    double cycles = 0.0;  // the fundamental's phase, in cycles
    for (int64_t t = first; t < last; ++t) {
      const double into_s = static_cast<double>(t) / fs - t_s, left_s = length_s - into_s;
      const double edge = std::min(1.0, std::min(into_s, left_s) / kEdge_s);
      const double envelope = gain * (0.5 - 0.5 * std::cos(std::numbers::pi * std::max(0.0, edge)));
      double v = 0.0;
      if (voiced) {
        cycles += (f_start + (f_end - f_start) * into_s / length_s) / fs;
        const double theta = kTwoPi * (cycles - std::floor(cycles));
        for (size_t k = 0; k < amplitude.size(); ++k)
          if (amplitude[k] > 0.0) v += amplitude[k] * std::cos(static_cast<double>(k + 1) * theta + phase[k]);
      } else {
        v = hiss[static_cast<size_t>(t)];
      }
      out[static_cast<size_t>(t)] = envelope * v;
    }
    // A voiced syllable gets the power gain^2, as an unvoiced one has (the hiss has unit power).
    if (voiced && last > first) {
      double power = 0.0;
      for (int64_t t = first; t < last; ++t) power += out[static_cast<size_t>(t)] * out[static_cast<size_t>(t)];
      power /= static_cast<double>(last - first);
      if (power > 0.0)
        for (int64_t t = first; t < last; ++t) out[static_cast<size_t>(t)] *= gain / std::sqrt(power);
    }
    t_s += length_s + draw(0.02, 0.08);
  }
  double power = 0.0;
  for (double v : out) power += v * v;
  power /= static_cast<double>(std::max<int64_t>(1, n));
  if (power > 0.0)
    for (double& v : out) v /= std::sqrt(power);
  return out;
}

}  // namespace localizer::engine
