#include "engine/sim/fractional_delay.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <vector>

namespace localizer::engine {
namespace {

// A sum of sinusoids with frequencies spread over (0.02, max_fraction) of fs: its value at any
// real position is known exactly, so it measures the interpolator against the true signal.
class Multitone {
 public:
  Multitone(double max_fraction, uint64_t seed) {
    std::mt19937_64 engine(seed);
    std::uniform_real_distribution<double> phase(0.0, 2.0 * std::numbers::pi);
    for (int i = 0; i < kTones; ++i) {
      frequencies_.push_back(0.02 + (max_fraction - 0.02) * (i + 0.5) / kTones);
      phases_.push_back(phase(engine));
    }
  }
  double operator()(double position) const {
    double value = 0.0;
    for (int i = 0; i < kTones; ++i) {
      value += std::cos(2.0 * std::numbers::pi * frequencies_[i] * position + phases_[i]);
    }
    return value;
  }
  double rms() const { return std::sqrt(0.5 * kTones); }

 private:
  static constexpr int kTones = 24;
  std::vector<double> frequencies_;
  std::vector<double> phases_;
};

// RMS interpolation error relative to the signal RMS, at random positions in the interior.
double RelativeRmsError(double max_fraction) {
  const Multitone signal(max_fraction, 7);
  const int size = 4096;
  std::vector<double> samples(size);
  for (int n = 0; n < size; ++n) samples[n] = signal(n);
  const FractionalDelayInterpolator interpolator;
  std::mt19937_64 engine(11);
  std::uniform_real_distribution<double> position(100.0, size - 100.0);
  double error_power = 0.0;
  const int trials = 20000;
  for (int i = 0; i < trials; ++i) {
    const double x = position(engine);
    const double error = interpolator.Evaluate(samples.data(), size, x) - signal(x);
    error_power += error * error;
  }
  return std::sqrt(error_power / trials) / signal.rms();
}

TEST(FractionalDelay, IntegerPositionsReproduceTheSamples) {
  std::vector<double> samples(200);
  std::mt19937_64 engine(3);
  std::normal_distribution<double> normal;
  for (double& v : samples) v = normal(engine);
  const FractionalDelayInterpolator interpolator;
  for (int n = 0; n < 200; ++n) {
    EXPECT_EQ(interpolator.Evaluate(samples.data(), 200, n), samples[n]) << n;
  }
}

TEST(FractionalDelay, ErrorIsSmallWellBelowNyquist) {
  const double below_030 = RelativeRmsError(0.30);
  const double below_036 = RelativeRmsError(0.36);
  const double below_040 = RelativeRmsError(0.40);
  const double below_045 = RelativeRmsError(0.45);
  std::printf(
      "relative RMS interpolation error: content to 0.30 fs %.2e, 0.36 fs %.2e, "
      "0.40 fs %.2e, 0.45 fs %.2e\n",
      below_030, below_036, below_040, below_045);
  EXPECT_LT(below_030, 2e-5);  // tetra-water, turn-multipath: 3000 / 11025 = 0.27 fs
  EXPECT_LT(below_036, 2e-5);  // the default band, 4000 / 11025 = 0.36 fs
  EXPECT_LT(below_040, 3e-5);  // the edge of the window's flat band
  EXPECT_GT(below_045, 1e-3);  // beyond it the error grows: band-limit the source
}

TEST(FractionalDelay, ShiftsAPulseByAFractionOfASample) {
  // A band-limited pulse sampled around 50; evaluated at 50 + 0.3 it must equal the pulse
  // shifted: compare the interpolated curve with the analytic one at several positions.
  const auto pulse = [](double x) {
    const double u = (x - 50.0) / 6.0;
    return std::exp(-0.5 * u * u) * std::cos(0.9 * (x - 50.0));
  };
  std::vector<double> samples(100);
  for (int n = 0; n < 100; ++n) samples[n] = pulse(n);
  const FractionalDelayInterpolator interpolator;
  for (int k = 0; 40.0 + 0.13 * k <= 60.0; ++k) {  // x = 40, 40.13, ..., 59.89
    const double x = 40.0 + 0.13 * k;
    EXPECT_NEAR(interpolator.Evaluate(samples.data(), 100, x), pulse(x), 1e-5) << x;
  }
}

TEST(FractionalDelay, SamplesBeyondTheEdgesCountAsZero) {
  std::vector<double> samples(64, 1.0);
  const FractionalDelayInterpolator interpolator;
  EXPECT_EQ(interpolator.Evaluate(samples.data(), 64, -40.0), 0.0);
  EXPECT_EQ(interpolator.Evaluate(samples.data(), 64, 120.5), 0.0);
  // At the first sample the value is exact; half a sample outside it is about half.
  EXPECT_DOUBLE_EQ(interpolator.Evaluate(samples.data(), 64, 0.0), 1.0);
  EXPECT_NEAR(interpolator.Evaluate(samples.data(), 64, -0.5), 0.5, 0.1);
}

}  // namespace
}  // namespace localizer::engine
