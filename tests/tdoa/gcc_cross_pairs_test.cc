// The pairs without the reference (GccOptions::cross_pairs_max_sensors): which arrays get
// them, where their GCC peaks (the true delay between their two sensors) and their noise
// scale, asserted against a tetrahedron's known geometry.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "engine/tdoa/gcc_layout.h"
#include "engine/tdoa/gcc_phat.h"
#include "tests/tdoa/tdoa_test_signals.h"

namespace localizer::engine {
namespace {

using testing::ChannelDelaysSamples;
using testing::DelayedNoiseFrame;
using testing::SignalSpec;

GccOptions CrossOptions(const SignalSpec& spec, int max_sensors) {
  GccOptions o;
  o.sample_rate_hz = spec.sample_rate_hz;
  o.frame_samples = spec.frame_samples;
  o.keep_gcc = true;
  o.cross_pairs_max_sensors = max_sensors;
  return o;
}

Measurement MeasureFrame(const ArrayGeometry& array, const GccOptions& options, const std::vector<float>& frame) {
  auto estimator = GccPhatEstimator::Create(array, options);
  EXPECT_TRUE(estimator.ok()) << estimator.status().ToString();
  Measurement m;
  EXPECT_TRUE((*estimator)->Estimate(frame.data(), options.frame_samples, 0.0, &m).ok());
  EXPECT_TRUE(m.cross_pairs.empty()) << "measured on request only";
  EXPECT_TRUE((*estimator)->MeasureCrossPairs(&m).ok());
  return m;
}

// Each cross pair (a, b) peaks at t_b - t_a, the same convention as the reference pairs, and
// reads noise on the reference pairs' scale.
TEST(CrossPairs, PeakAtTheDelayBetweenTheirTwoSensors) {
  const ArrayGeometry array = testing::TetrahedronArray();
  const SignalSpec spec;
  const Vec3 source(4.0, -2.5, 1.5);
  const std::vector<double> delays = ChannelDelaysSamples(array, source, spec.sample_rate_hz);
  const Measurement m = MeasureFrame(array, CrossOptions(spec, 4), DelayedNoiseFrame(spec, delays, 10.0, /*seed=*/21));
  ASSERT_EQ(m.cross_pairs.size(), 3u);  // (1, 2), (1, 3), (2, 3)
  const int expected[3][2] = {{1, 2}, {1, 3}, {2, 3}};
  for (size_t q = 0; q < m.cross_pairs.size(); ++q) {
    const CrossPairGcc& cp = m.cross_pairs[q];
    EXPECT_EQ(cp.sensor_a, expected[q][0]);
    EXPECT_EQ(cp.sensor_b, expected[q][1]);
    const int half = -cp.first_lag_samples;
    ASSERT_EQ(cp.gcc.size(), static_cast<size_t>(2 * half + 1));
    const double baseline_m = (array.sensor_m(cp.sensor_a) - array.sensor_m(cp.sensor_b)).norm();
    EXPECT_GE(half, std::ceil(baseline_m / array.sound_speed_mps() * spec.sample_rate_hz));
    const auto peak = std::max_element(cp.gcc.begin(), cp.gcc.end()) - cp.gcc.begin();
    const double true_lag = delays[static_cast<size_t>(cp.sensor_b)] - delays[static_cast<size_t>(cp.sensor_a)];
    EXPECT_NEAR(static_cast<double>(cp.first_lag_samples + peak), true_lag, 0.51)
        << "pair (" << cp.sensor_a << ", " << cp.sensor_b << ")";
    // A clean 10 dB peak stands far above the noise-only spread.
    EXPECT_GT(cp.gcc[static_cast<size_t>(peak)] * cp.noise_floor_inverse, 20.0);
    EXPECT_NEAR(cp.noise_floor_inverse, m.pairs[0].peak_snr / m.pairs[0].peak_value, 1e-3 * cp.noise_floor_inverse);
  }
}

// Only arrays up to the stated size, and only when the GCC is kept; the reference pairs are
// the same with or without them.
TEST(CrossPairs, OnlySmallArraysThatKeepTheirGcc) {
  const SignalSpec spec;
  const ArrayGeometry tetra = testing::TetrahedronArray();
  const std::vector<float> frame =
      DelayedNoiseFrame(spec, ChannelDelaysSamples(tetra, Vec3(3, 3, -1), spec.sample_rate_hz), 5.0, 4);
  const Measurement without = MeasureFrame(tetra, CrossOptions(spec, 0), frame);
  const Measurement with = MeasureFrame(tetra, CrossOptions(spec, 4), frame);
  EXPECT_TRUE(without.cross_pairs.empty());
  ASSERT_EQ(with.pairs.size(), without.pairs.size());
  for (size_t p = 0; p < with.pairs.size(); ++p) {
    EXPECT_EQ(with.pairs[p].delay_s, without.pairs[p].delay_s);
    EXPECT_EQ(with.pairs[p].gcc, without.pairs[p].gcc);
  }
  GccOptions dropped = CrossOptions(spec, 4);
  dropped.keep_gcc = false;
  EXPECT_TRUE(MeasureFrame(tetra, dropped, frame).cross_pairs.empty());

  std::vector<Vec3> five = testing::TetrahedronSensors();
  five.push_back(Vec3(0.0, 0.0, 0.0));
  const ArrayGeometry pentad = *ArrayGeometry::Create(five, 1500.0);
  EXPECT_TRUE((*ComputeGccLayout(pentad, CrossOptions(spec, 4))).cross_sensors.empty());
  const GccLayout layout = *ComputeGccLayout(pentad, CrossOptions(spec, 5));
  EXPECT_EQ(layout.cross_sensors.size(), 6u);  // 4 non-reference sensors: 4 * 3 / 2
  // No cross window reaches lags where the circular correlation aliases.
  for (int half : layout.cross_max_lag_samples) {
    EXPECT_LE(half + kPeakHalfWidth + spec.frame_samples + 1, layout.fft_size);
  }
}

// cross_pairs_with_frame: Estimate measures them, packed with the reference pairs' transforms
// (packed_transforms.h), to float rounding what a request measures; with delay rates set they
// stay on request (a warped reading may still replace a channel's spectrum).
TEST(CrossPairs, MeasuredWithTheFrameWhenAskedAsOnRequest) {
  const SignalSpec spec;
  const ArrayGeometry tetra = testing::TetrahedronArray();
  const std::vector<float> frame =
      DelayedNoiseFrame(spec, ChannelDelaysSamples(tetra, Vec3(-2, 3, 1), spec.sample_rate_hz), 5.0, 9);
  const Measurement requested = MeasureFrame(tetra, CrossOptions(spec, 4), frame);
  GccOptions eager = CrossOptions(spec, 4);
  eager.cross_pairs_with_frame = true;
  auto estimator = *GccPhatEstimator::Create(tetra, eager);
  Measurement m;
  ASSERT_TRUE(estimator->Estimate(frame.data(), spec.frame_samples, 0.0, &m).ok());
  ASSERT_EQ(m.cross_pairs.size(), requested.cross_pairs.size());
  ASSERT_EQ(m.cross_pairs.size(), 3u);
  for (size_t q = 0; q < m.cross_pairs.size(); ++q) {
    ASSERT_EQ(m.cross_pairs[q].gcc.size(), requested.cross_pairs[q].gcc.size());
    for (size_t i = 0; i < m.cross_pairs[q].gcc.size(); ++i) {
      EXPECT_NEAR(m.cross_pairs[q].gcc[i], requested.cross_pairs[q].gcc[i], 1e-5) << q << " " << i;
    }
  }
  ASSERT_TRUE(estimator->SetDelayRates(std::vector<double>{1e-4, 0.0, 0.0}).ok());
  ASSERT_TRUE(estimator->Estimate(frame.data(), spec.frame_samples, 0.0, &m).ok());
  EXPECT_TRUE(m.cross_pairs.empty()) << "on request while delay rates are set";
  ASSERT_TRUE(estimator->MeasureCrossPairs(&m).ok());
  EXPECT_EQ(m.cross_pairs.size(), 3u);
}

TEST(CrossPairs, AskedBeforeAFrameIsAFailedPrecondition) {
  const SignalSpec spec;
  auto estimator = *GccPhatEstimator::Create(testing::TetrahedronArray(), CrossOptions(spec, 4));
  Measurement m;
  EXPECT_EQ(estimator->MeasureCrossPairs(&m).code(), StatusCode::kFailedPrecondition);
  EXPECT_EQ(estimator->MeasureCrossPairs(nullptr).code(), StatusCode::kInvalidArgument);
}

TEST(CrossPairs, TheOptionIsValidatedNamingIt) {
  GccOptions o = CrossOptions(SignalSpec{}, 17);
  const Status s = o.Validate();
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("cross_pairs_max_sensors"), std::string::npos) << s.message();
}

}  // namespace
}  // namespace localizer::engine
