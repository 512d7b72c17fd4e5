// The speech-like talker (engine/sim/speech_like.h) has what its header promises and band
// noise lacks: unit power, most of it below 1 kHz, nothing outside its band, a pitch in its
// voiced syllables, and short silences between syllables; a seed replays it.
#include "engine/sim/speech_like.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "engine/sim/band_pass_fir.h"

namespace localizer::engine {
namespace {

constexpr double kFs = 16000.0;
constexpr int64_t kN = 160000;  // 10 s

double Power(const std::vector<double>& x) {
  double p = 0.0;
  for (double v : x) p += v * v;
  return p / static_cast<double>(x.size());
}

double BandPower(const std::vector<double>& x, double low_hz, double high_hz) {
  return Power(FilterValid(x, DesignBandPassFir(low_hz, high_hz, kFs).taps));
}

// Median over 32-ms windows holding sound of the largest normalised autocorrelation at lags
// of 90-250 Hz periods: near 1 for a voiced (periodic) window, small for noise.
double MedianPitchCorrelation(const std::vector<double>& x) {
  const int window = 512, lo = static_cast<int>(kFs / 250.0), hi = static_cast<int>(kFs / 90.0);
  std::vector<double> best;
  for (size_t start = 0; start + window + hi < x.size(); start += window) {
    double energy = 0.0;
    for (int t = 0; t < window; ++t) energy += x[start + t] * x[start + t];
    if (energy < 0.1 * window) continue;  // a gap or an edge
    double top = 0.0;
    for (int lag = lo; lag <= hi; ++lag) {
      double c = 0.0, e2 = 0.0;
      for (int t = 0; t < window; ++t)
        c += x[start + t] * x[start + t + lag], e2 += x[start + t + lag] * x[start + t + lag];
      top = std::max(top, c / std::sqrt(energy * e2 + 1e-300));
    }
    best.push_back(top);
  }
  std::nth_element(best.begin(), best.begin() + best.size() / 2, best.end());
  return best[best.size() / 2];
}

TEST(SpeechLike, HasUnitPowerMostlyBelowOneKilohertzAndNothingOutsideItsBand) {
  std::mt19937_64 rng(7);
  const std::vector<double> x = SpeechLikeSignal(100.0, 4000.0, kFs, kN, &rng);
  ASSERT_EQ(static_cast<int64_t>(x.size()), kN);
  EXPECT_NEAR(Power(x), 1.0, 1e-9);
  const double below_1k = BandPower(x, 50.0, 1000.0);
  const double above_band = BandPower(x, 4600.0, 7900.0);
  std::printf("power below 1 kHz %.2f, above 4.6 kHz %.2g\n", below_1k, above_band);
  EXPECT_GT(below_1k, 0.5);
  EXPECT_LT(above_band, 0.01);
}

TEST(SpeechLike, VoicedSyllablesHaveAPitchAndSyllablesAreSeparatedBySilence) {
  std::mt19937_64 rng(11);
  const std::vector<double> speech = SpeechLikeSignal(100.0, 7000.0, kFs, kN, &rng);
  std::vector<double> noise(static_cast<size_t>(kN));
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (double& v : noise) v = gauss(rng);
  noise = FilterValid(noise, DesignBandPassFir(100.0, 7000.0, kFs).taps);
  const double speech_pitch = MedianPitchCorrelation(speech), noise_pitch = MedianPitchCorrelation(noise);
  std::printf("median pitch correlation: speech-like %.2f, band noise %.2f\n", speech_pitch, noise_pitch);
  EXPECT_GT(speech_pitch, 0.6);
  EXPECT_LT(noise_pitch, 0.35);
  // 10-ms windows with (almost) nothing: the 20-80 ms gaps between 0.12-0.25 s syllables.
  int silent = 0, windows = 0;
  for (size_t start = 0; start + 160 <= speech.size(); start += 160, ++windows) {
    double e = 0.0;
    for (size_t t = start; t < start + 160; ++t) e += speech[t] * speech[t];
    silent += e < 1e-6 * 160;
  }
  EXPECT_GT(silent, windows / 20);
  EXPECT_LT(silent, windows * 2 / 5);
}

TEST(SpeechLike, ASeedReplays) {
  std::mt19937_64 a(3), b(3), c(4);
  const std::vector<double> x = SpeechLikeSignal(100.0, 7000.0, kFs, 16000, &a);
  EXPECT_EQ(x, SpeechLikeSignal(100.0, 7000.0, kFs, 16000, &b));
  EXPECT_NE(x, SpeechLikeSignal(100.0, 7000.0, kFs, 16000, &c));
}

}  // namespace
}  // namespace localizer::engine
