// Closure of a 4-sensor array's pairs (pair_closure.h): the pairs without the reference move
// a reference pair whose peak they contradict, and leave agreeing frames exactly as they were.
#include "engine/acquisition/pair_closure.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "tests/tdoa/cross_pair_frames.h"
#include "tests/tdoa/tdoa_test_signals.h"

namespace localizer::engine {
namespace {

using testing::ChannelDelaysSamples;
using testing::DelayedNoiseFrame;
using testing::MultipathFrame;
using testing::Path;
using testing::SignalSpec;

// A tetrahedron's frame with the source at 10 dB, measured with the cross pairs; channels 0
// and 3 share crosstalk at `crosstalk_gain` x the source's level (0: none).
Measurement TetrahedronFrame(const Vec3& source_m, double crosstalk_gain, std::vector<double>* true_lags) {
  const auto array = testing::TetrahedronArray();
  const SignalSpec spec;
  *true_lags = ChannelDelaysSamples(array, source_m, spec.sample_rate_hz);
  std::vector<float> frame = DelayedNoiseFrame(spec, *true_lags, 10.0, /*seed=*/31);
  if (crosstalk_gain > 0.0) {
    const std::vector<float> crosstalk =
        MultipathFrame(spec, {{Path{0.0, 1.0}}, {}, {}, {Path{0.0, 1.0}}}, testing::kNoiseless, /*seed=*/32);
    for (size_t i = 0; i < frame.size(); ++i) frame[i] += static_cast<float>(crosstalk_gain) * crosstalk[i];
  }
  return testing::MeasureWithCrossPairs(array, spec, frame, 4);
}

// Crosstalk louder than the source makes pair (0, 3) peak at lag 0, through which the three
// reference pairs have an exact, wrong, position. Its own GCC still shows the direct path,
// where the cross pairs (1, 3) and (2, 3) agree: the pair is moved there.
TEST(PairClosure, MovesAPairOnCrosstalkToWhereTheOtherPairsAgree) {
  std::vector<double> lags;
  Measurement m = TetrahedronFrame(Vec3(5.0, 3.0, -1.0), 1.5, &lags);
  const double fs = m.sample_rate_hz;
  ASSERT_GT(std::abs(lags[3]), 4.0) << "pair (0, 3)'s true lag must lie away from the crosstalk's 0";
  ASSERT_NEAR(m.pairs[2].delay_s * fs, 0.0, 0.5) << "the crosstalk leads pair (0, 3)";
  const Measurement before = m;
  const ClosureRepair r = PairClosure().Repair(&m);
  ASSERT_EQ(r.pair, 2);
  EXPECT_TRUE(r.own_peak);
  EXPECT_NEAR(m.pairs[2].delay_s * fs, lags[3], 0.3);
  EXPECT_TRUE(m.pairs[2].confirmed);
  EXPECT_EQ(m.pairs[2].delay_sigma_s, 0.0) << "from the new peak's curvature";
  for (int p = 0; p < 2; ++p) EXPECT_EQ(m.pairs[p].delay_s, before.pairs[p].delay_s) << "pair " << p;
  std::printf("pair (0, 3) moved from lag %.2f to %.2f (true %.2f), consensus gain %.1f sds\n", r.from_s * fs,
              r.to_s * fs, lags[3], r.gain);
}

TEST(PairClosure, LeavesAFrameWhosePairsAgreeAsItWas) {
  std::vector<double> lags;
  Measurement m = TetrahedronFrame(Vec3(5.0, 3.0, -1.0), 0.0, &lags);
  const Measurement before = m;
  EXPECT_EQ(PairClosure().Repair(&m).pair, -1);
  for (size_t p = 0; p < m.pairs.size(); ++p) {
    EXPECT_EQ(m.pairs[p].delay_s, before.pairs[p].delay_s);
    EXPECT_EQ(m.pairs[p].delay_sigma_s, before.pairs[p].delay_sigma_s);
    EXPECT_EQ(m.pairs[p].confirmed, before.pairs[p].confirmed);
    EXPECT_NEAR(m.pairs[p].delay_s * m.sample_rate_hz, lags[p + 1], 0.3);
  }
}

TEST(PairClosure, WithoutCrossPairsNothingIsChecked) {
  std::vector<double> lags;
  Measurement m = TetrahedronFrame(Vec3(5.0, 3.0, -1.0), 1.5, &lags);
  m.cross_pairs.clear();
  EXPECT_EQ(PairClosure().Repair(&m).pair, -1);
  EXPECT_NEAR(m.pairs[2].delay_s * m.sample_rate_hz, 0.0, 0.5);
}

// Synthetic GCCs (normalised noise sd 1 after the field's scaling): each listed peak is a
// Gaussian of 1.5 samples' width. Sensors 1..3 against the reference 0; lags in samples.
constexpr double kFs = 16000.0;
constexpr int kFirstLag = -80, kLags = 161;
constexpr double kNoise = 0.01;  // the GCC's noise-only sd

std::vector<float> SyntheticGcc(const std::vector<std::pair<double, double>>& peaks, std::mt19937* rng) {
  std::normal_distribution<double> noise(0.0, kNoise);
  std::vector<float> g(kLags);
  for (int i = 0; i < kLags; ++i) {
    double v = noise(*rng);
    for (const auto& [lag, height] : peaks) v += height * std::exp(-0.5 * std::pow((kFirstLag + i - lag) / 1.5, 2));
    g[static_cast<size_t>(i)] = static_cast<float>(v);
  }
  return g;
}

// Reference pair peaks as listed per pair (the tallest first), cross pairs peaking where the
// true lags close, each 0.3 high (30 noise sds).
Measurement SyntheticFrame(const std::vector<double>& true_lags,
                           const std::vector<std::vector<std::pair<double, double>>>& reference_peaks) {
  std::mt19937 rng(7);
  Measurement m;
  m.sample_rate_hz = kFs;
  for (int p = 0; p < 3; ++p) {
    PairMeasurement pair;
    pair.sensor = p + 1;
    pair.delay_s = reference_peaks[static_cast<size_t>(p)].front().first / kFs;
    pair.peak_value = reference_peaks[static_cast<size_t>(p)].front().second;
    pair.peak_snr = pair.peak_value / kNoise;
    pair.delay_sigma_s = 0.1 / kFs;
    pair.first_lag_samples = kFirstLag;
    pair.gcc = SyntheticGcc(reference_peaks[static_cast<size_t>(p)], &rng);
    m.pairs.push_back(pair);
  }
  for (int a = 1; a <= 3; ++a) {
    for (int b = a + 1; b <= 3; ++b) {
      CrossPairGcc cp;
      cp.sensor_a = a;
      cp.sensor_b = b;
      cp.noise_floor_inverse = 1.0 / kNoise;
      cp.first_lag_samples = kFirstLag;
      cp.gcc =
          SyntheticGcc({{true_lags[static_cast<size_t>(b - 1)] - true_lags[static_cast<size_t>(a - 1)], 0.3}}, &rng);
      m.cross_pairs.push_back(cp);
    }
  }
  return m;
}

// Pair 2's own GCC has no path at its true lag (smeared, masked) and a peak elsewhere: it is
// read where the cross pairs and the two other reference pairs agree, with the sigma of a
// witness's path (sqrt 2 x the smallest witness sigma).
TEST(PairClosure, APairWithoutAPathOfItsOwnIsReadThroughItsWitnesses) {
  const std::vector<double> truth = {-20.0, 12.4, 33.7};
  Measurement m = SyntheticFrame(truth, {{{-20.0, 0.3}}, {{12.4, 0.3}}, {{-41.0, 0.2}}});
  const ClosureRepair r = PairClosure().Repair(&m);
  ASSERT_EQ(r.pair, 2);
  EXPECT_FALSE(r.own_peak);
  EXPECT_NEAR(m.pairs[2].delay_s * kFs, 33.7, 0.3);
  EXPECT_NEAR(m.pairs[2].delay_sigma_s * kFs, std::sqrt(2.0) * 0.1, 1e-9);
  EXPECT_NEAR(m.pairs[0].delay_s * kFs, -20.0, 1e-9);
  EXPECT_NEAR(m.pairs[1].delay_s * kFs, 12.4, 1e-9);
}

// With an own path at the truth (weaker than its echo), the pair is moved onto that path
// (12 noise sds high: a parabola's read within 0.4 samples).
TEST(PairClosure, APairOnItsEchoIsMovedOntoItsOwnDirectPath) {
  const std::vector<double> truth = {-20.0, 12.4, 33.7};
  Measurement m = SyntheticFrame(truth, {{{-20.0, 0.3}}, {{12.4, 0.3}}, {{-41.0, 0.25}, {33.7, 0.12}}});
  const ClosureRepair r = PairClosure().Repair(&m);
  ASSERT_EQ(r.pair, 2);
  EXPECT_TRUE(r.own_peak);
  EXPECT_NEAR(m.pairs[2].delay_s * kFs, 33.7, 0.4);
  EXPECT_EQ(m.pairs[2].delay_sigma_s, 0.0);
}

// Two reference pairs off leave no majority of witnesses: nothing moves.
TEST(PairClosure, TwoContradictedPairsAreLeftAlone) {
  const std::vector<double> truth = {-20.0, 12.4, 33.7};
  Measurement m = SyntheticFrame(truth, {{{-20.0, 0.3}}, {{50.0, 0.3}, {12.4, 0.1}}, {{-41.0, 0.25}, {33.7, 0.12}}});
  EXPECT_EQ(PairClosure().Repair(&m).pair, -1);
  EXPECT_NEAR(m.pairs[1].delay_s * kFs, 50.0, 1e-9);
  EXPECT_NEAR(m.pairs[2].delay_s * kFs, -41.0, 1e-9);
}

}  // namespace
}  // namespace localizer::engine
