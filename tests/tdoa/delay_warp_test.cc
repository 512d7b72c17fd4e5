// Reading a channel along a changing delay (delay_warp.h, GccPhatEstimator::SetDelayRates):
// the warp is exact at rate 0 and reads a band-limited signal where its argument says; a
// pair whose delay moves 24 samples over a frame peaks at the frame centre's delay, with a
// taller peak, once its rate is given, and keeps its plain reading under a wrong rate; bad
// rates are refused.
#include "engine/tdoa/delay_warp.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "engine/tdoa/gcc_phat.h"

namespace localizer::engine {
namespace {

constexpr double kSampleRateHz = 48000.0;
constexpr int kFrame = 4096;
constexpr double kCentre = 0.5 * (kFrame - 1);

std::vector<Vec3> Tetrahedron() { return {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)}; }

// A broadband source as a sum of seeded random tones in [low, high] Hz, evaluated at any
// (fractional) sample time: delays need no interpolation.
struct Tones {
  std::vector<double> omega, phase;
  Tones(int count, double low_hz, double high_hz, uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> f(low_hz, high_hz), p(0.0, 2.0 * std::numbers::pi);
    for (int i = 0; i < count; ++i) {
      omega.push_back(2.0 * std::numbers::pi * f(rng) / kSampleRateHz);
      phase.push_back(p(rng));
    }
  }
  double At(double n) const {
    double v = 0.0;
    for (size_t i = 0; i < omega.size(); ++i) v += std::cos(omega[i] * n + phase[i]);
    return v / std::sqrt(0.5 * omega.size());
  }
};

TEST(DelayWarp, RateZeroCopiesTheChannel) {
  std::vector<float> in(kFrame), out(kFrame);
  std::mt19937_64 rng(7);
  std::normal_distribution<float> g;
  for (float& v : in) v = g(rng);
  WarpChannel(in.data(), kFrame, 0.0, out.data());
  EXPECT_EQ(in, out);
}

// Tones up to a tenth of the sample rate, read at n + rate (n - c): within 1 % rms of the
// signal evaluated there (Catmull-Rom's error at 0.1 fs), away from the clamped ends.
TEST(DelayWarp, ReadsABandLimitedSignalAtTheWarpedTimes) {
  const Tones tones(64, 200.0, 4800.0, 11);
  std::vector<float> in(kFrame), out(kFrame);
  for (int n = 0; n < kFrame; ++n) in[n] = static_cast<float>(tones.At(n));
  for (const double rate : {0.004, -0.007}) {
    WarpChannel(in.data(), kFrame, rate, out.data());
    double err2 = 0.0, sig2 = 0.0;
    for (int n = 64; n < kFrame - 64; ++n) {
      const double want = tones.At(n + rate * (n - kCentre));
      err2 += (out[n] - want) * (out[n] - want);
      sig2 += want * want;
    }
    EXPECT_LT(std::sqrt(err2 / sig2), 0.01) << "rate " << rate;
  }
}

// Microphones 1 m apart at 48 kHz; the second hears the source d(n) = 40 + r (n - c) samples
// after the first, r = 24 / 4096 (a 1 m/s source between them): the peak moves 24 samples over
// the frame (the other two hear it with the first). With the rate given, the pair peaks within
// 0.1 sample of the centre's delay, and taller than without it (measured: 38.0 samples at peak
// 0.074 as it is, 40.05 at 0.324 read along the rate).
TEST(DelayWarp, AGivenRateFocusesAMigratingPeakOnTheCentresDelay) {
  const ArrayGeometry array = *ArrayGeometry::Create(Tetrahedron(), 343.0);
  const Tones tones(400, 500.0, 12000.0, 3);
  const double delay_samples = 40.0;
  const double rate = 24.0 / kFrame;
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 0.3);  // about 10 dB
  std::vector<float> frame(4 * kFrame);
  for (int n = 0; n < kFrame; ++n) {
    frame[kFrame + n] = static_cast<float>(tones.At(n - delay_samples - rate * (n - kCentre)) + noise(rng));
    for (const int ch : {0, 2, 3}) frame[ch * kFrame + n] = static_cast<float>(tones.At(n) + noise(rng));
  }
  GccOptions options;
  options.sample_rate_hz = kSampleRateHz;
  options.frame_samples = kFrame;
  options.taper_fraction = 1.0;
  auto estimator = GccPhatEstimator::Create(array, options);
  ASSERT_TRUE(estimator.ok()) << estimator.status().ToString();
  Measurement plain, focused;
  ASSERT_TRUE((*estimator)->Estimate(frame.data(), kFrame, 0.0, &plain).ok());
  const std::vector<double> rates = {rate, 0.0, 0.0};
  ASSERT_TRUE((*estimator)->SetDelayRates(rates).ok());
  ASSERT_TRUE((*estimator)->Estimate(frame.data(), kFrame, 0.0, &focused).ok());
  EXPECT_NEAR(focused.pairs[0].delay_s * kSampleRateHz, delay_samples, 0.1);
  EXPECT_GT(focused.pairs[0].peak_value, 2.0 * plain.pairs[0].peak_value)
      << "plain delay " << plain.pairs[0].delay_s * kSampleRateHz << " samples";
  // The opposite rate smears the peak twice as far: the plain reading is kept, bit for bit.
  const std::vector<double> wrong = {-rate, 0.0, 0.0};
  ASSERT_TRUE((*estimator)->SetDelayRates(wrong).ok());
  Measurement kept;
  ASSERT_TRUE((*estimator)->Estimate(frame.data(), kFrame, 0.0, &kept).ok());
  EXPECT_EQ(kept.pairs[0].delay_s, plain.pairs[0].delay_s);
  EXPECT_EQ(kept.pairs[0].peak_value, plain.pairs[0].peak_value);
  // Cleared: the frame reads as it did.
  ASSERT_TRUE((*estimator)->SetDelayRates({}).ok());
  Measurement again;
  ASSERT_TRUE((*estimator)->Estimate(frame.data(), kFrame, 0.0, &again).ok());
  EXPECT_EQ(again.pairs[0].delay_s, plain.pairs[0].delay_s);
}

TEST(DelayWarp, BadRatesAreRefused) {
  const ArrayGeometry array = *ArrayGeometry::Create(Tetrahedron(), 343.0);
  GccOptions options;
  options.sample_rate_hz = kSampleRateHz;
  options.frame_samples = 1024;
  auto estimator = GccPhatEstimator::Create(array, options);
  ASSERT_TRUE(estimator.ok());
  const std::vector<double> two = {0.001, 0.0};
  const std::vector<double> nan = {0.001, std::nan(""), 0.0};
  const std::vector<double> fast = {0.001, 0.06, 0.0};
  EXPECT_EQ((*estimator)->SetDelayRates(two).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ((*estimator)->SetDelayRates(nan).code(), StatusCode::kInvalidArgument);
  const Status s = (*estimator)->SetDelayRates(fast);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("pair 1"), std::string::npos) << s.message();
  const std::vector<double> ok = {0.001, -0.002, 0.0};
  EXPECT_TRUE((*estimator)->SetDelayRates(ok).ok());
}

}  // namespace
}  // namespace localizer::engine
