// The soft-iron fit on simulated fields whose distortion and offset are known, and the
// quaternion filter with iron riding on a simulated tumbling sensor, with and without the fit
// (engine/attitude/soft_iron_estimator.h, engine/sim/magnetic_disturbance.h). Seeds fixed;
// tolerances stated per test.
#include "engine/attitude/soft_iron_estimator.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "engine/attitude/quaternion_ekf.h"
#include "engine/sim/magnetic_disturbance.h"
#include "tests/attitude/attitude_test_util.h"
#include "tests/attitude/iron_fixtures.h"

namespace localizer::engine {
namespace {

using testing::ConsumerImuNoise;
using testing::kDeg;

using testing::kEarthField_uT;
using testing::kOffset_uT;
using testing::kRateHz;
using testing::Tumbling;

// A ±5 % soft-iron matrix (principal gains 0.95..1.05), fixed.
Eigen::Matrix3d FivePercentSoftIron() {
  Eigen::Matrix3d s;
  s << 1.04, 0.02, -0.03, 0.02, 0.96, 0.015, -0.03, 0.015, 1.01;
  return s;
}

struct Fits {
  HardIronFit hard;
  SoftIronFit soft;
};

// Feeds `seconds` of readings m = S R^T m_w + o + noise (0.5 µT) at the true attitude into the
// hard-iron estimator with the filter's defaults, and fits both models to its sums.
Fits FitOver(const AttitudeTrajectory& truth, double seconds, const Eigen::Matrix3d& soft_iron) {
  HardIronEstimator estimator(20.0, 0.1, 0.1);  // the defaults
  std::mt19937_64 engine(5);
  std::normal_distribution<double> noise(0.0, 0.5);
  Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
  for (int k = 0; k < static_cast<int>(seconds * kRateHz); ++k) {
    r = truth.At(k / kRateHz).toRotationMatrix();
    const Eigen::Vector3d m = soft_iron * (r.transpose() * kEarthField_uT) + kOffset_uT +
                              Eigen::Vector3d(noise(engine), noise(engine), noise(engine));
    estimator.Add(r, m, 1.0 / kRateHz);
  }
  return {estimator.Solve(r), FitSoftIron(estimator.sums(), SoftIronLimits{})};
}

// A S should be the identity up to the scale the fit cannot see: its largest entry off c I,
// c = trace(A S) / 3.
double ShapeError(const Eigen::Matrix3d& correction, const Eigen::Matrix3d& soft_iron) {
  const Eigen::Matrix3d product = correction * soft_iron;
  return (product / (product.trace() / 3.0) - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
}

// Turning over the sphere for 30 s: the distortion's shape to 0.005 (measured in the print),
// the offset to 0.3 µT, trusted; the hard-iron fit's residual shows what it leaves.
TEST(SoftIronEstimatorTest, RecoversTheDistortionFromRotation) {
  const Fits fits = FitOver(Tumbling(), 30.0, FivePercentSoftIron());
  std::printf(
      "soft: diversity %.3f residual %.2f uT shape %.4f offset error %.3f uT | hard: diversity %.3f "
      "residual %.2f uT offset error %.2f uT\n",
      fits.soft.diversity, fits.soft.residual_uT, ShapeError(fits.soft.correction, FivePercentSoftIron()),
      (fits.soft.offset_uT - kOffset_uT).norm(), fits.hard.diversity, fits.hard.residual_uT,
      (fits.hard.offset_uT - kOffset_uT).norm());
  EXPECT_TRUE(fits.soft.trusted);
  EXPECT_LT(ShapeError(fits.soft.correction, FivePercentSoftIron()), 0.005);
  EXPECT_LT((fits.soft.offset_uT - kOffset_uT).norm(), 0.3);
  EXPECT_LT(fits.soft.residual_uT, 1.0);  // the noise: 0.87 µT per sample
  EXPECT_GT(fits.hard.residual_uT, 1.5 * fits.soft.residual_uT);
}

// A clean sensor: the correction is the identity to 0.005 (below the 0.01 the filter acts on).
TEST(SoftIronEstimatorTest, ACleanSensorFitsTheIdentity) {
  const Fits fits = FitOver(Tumbling(), 30.0, Eigen::Matrix3d::Identity());
  EXPECT_TRUE(fits.soft.trusted);
  EXPECT_LT((fits.soft.correction - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), 0.005);
  EXPECT_LT((fits.soft.offset_uT - kOffset_uT).norm(), 0.3);
}

// Still: nothing separates a distortion, an offset and the world field.
TEST(SoftIronEstimatorTest, NoRotationIsNotTrusted) {
  const Fits fits =
      FitOver(AttitudeTrajectory::ConstantRate({0.1, 0.2, 0.3}, Eigen::Vector3d::Zero()), 30.0, FivePercentSoftIron());
  EXPECT_FALSE(fits.soft.trusted);
  EXPECT_LT(fits.soft.diversity, 0.01);  // noise alone (measured 2e-4)
}

// Yaw swinging with little tilt (a hand-held sensor turned about the vertical): enough for the
// hard-iron fit, not for the soft-iron one: the distortion's part along the vertical is
// unobserved, so the filter keeps to hard iron.
TEST(SoftIronEstimatorTest, TurningAboutOneAxisIsNotEnough) {
  AttitudeTrajectoryOptions motion;
  motion.amplitude_rad = {0.35, 0.35, 2.5};
  motion.frequency_hz = {0.13, 0.07, 0.05};
  const Fits fits = FitOver(AttitudeTrajectory(motion), 30.0, FivePercentSoftIron());
  std::printf("hard diversity %.3f, soft diversity %.3f\n", fits.hard.diversity, fits.soft.diversity);
  EXPECT_GE(fits.hard.diversity, 0.1);
  EXPECT_LT(fits.soft.diversity, SoftIronLimits{}.min_diversity);
  EXPECT_FALSE(fits.soft.trusted);
}

// RMS heading error of a fresh filter over `samples` from `from_s` on.
double RmsHeadingDeg(const AttitudeFilterOptions& options, const AttitudeTrajectory& truth,
                     const std::vector<ImuSample>& samples, double from_s) {
  QuaternionEkf filter(options);
  double sum = 0.0;
  int count = 0;
  for (const ImuSample& s : samples) {
    EXPECT_TRUE(filter.Update(s).ok());
    if (s.t_s < from_s) continue;
    const double e = AttitudeErrorOf(filter.estimate().body_to_world, truth.At(s.t_s)).heading_rad;
    sum += e * e;
    ++count;
  }
  return std::sqrt(sum / std::max(count, 1)) / kDeg;
}

// A 40 µT magnet with ±5 % soft iron (RandomSoftIronMagnet, three seeded draws) on a tumbling
// simulated sensor from the first sample, 120 s: from 60 s on the RMS heading error, mean of
// the draws, is below 0.6 deg with the soft-iron fit (measured 0.43, the clean sensor 0.28:
// 1.5x the clean error, within rounding); with hard iron only (mag_soft_iron_max = 0) the
// distortion stays in the heading and the bound fails (measured 0.79). Draw 10 is the worst
// (0.72 against 0.98 hard only): its first correction comes from a window where the heading
// was still following the distorted field.
TEST(SoftIronEstimatorTest, FilterRemovesTheSoftIronHeadingError) {
  const AttitudeTrajectory truth = Tumbling();
  AttitudeFilterOptions options;
  options.use_mag = true;
  AttitudeFilterOptions hard_only = options;
  hard_only.mag_soft_iron_max = 0.0;
  double clean_deg = 0.0, fit_deg = 0.0, hard_deg = 0.0;
  for (const uint64_t seed : {9u, 10u, 11u}) {
    const std::vector<ImuSample> clean = SynthesiseImu(truth, kRateHz, 120.0, ConsumerImuNoise(), 20 + seed);
    std::vector<ImuSample> samples = clean;
    AddBodyFixedMagnet(RandomSoftIronMagnet(40.0, 0.05, 0.0, seed), &samples);
    const double c = RmsHeadingDeg(options, truth, clean, 60.0);
    const double f = RmsHeadingDeg(options, truth, samples, 60.0);
    const double h = RmsHeadingDeg(hard_only, truth, samples, 60.0);
    std::printf(
        "draw %lu: RMS heading error from 60 s: clean %.2f deg, with the soft-iron fit %.2f, hard iron "
        "only %.2f\n",
        static_cast<unsigned long>(seed), c, f, h);
    clean_deg += c / 3.0;
    fit_deg += f / 3.0;
    hard_deg += h / 3.0;
  }
  std::printf("means: clean %.2f deg, with the fit %.2f, hard iron only %.2f\n", clean_deg, fit_deg, hard_deg);
  EXPECT_LT(fit_deg, 0.6);
}

// The filter adopts the correction it finds (and says so in its estimate).
TEST(SoftIronEstimatorTest, FilterReportsTheCorrection) {
  const AttitudeTrajectory truth = Tumbling();
  std::vector<ImuSample> samples = SynthesiseImu(truth, kRateHz, 120.0, ConsumerImuNoise(), 29);
  const BodyFixedMagnet magnet = RandomSoftIronMagnet(40.0, 0.05, 0.0, 9);
  AddBodyFixedMagnet(magnet, &samples);
  AttitudeFilterOptions options;
  options.use_mag = true;
  const AttitudeEstimate last = testing::RunFilter(options, truth, samples).last;
  EXPECT_TRUE(last.mag_calibrated);
  EXPECT_LT(ShapeError(last.mag_correction, magnet.soft_iron), 0.01);
  EXPECT_LT((last.mag_offset_uT - magnet.offset_uT).norm(), 1.0);
}

}  // namespace
}  // namespace localizer::engine
