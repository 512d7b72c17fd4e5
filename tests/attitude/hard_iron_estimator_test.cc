// The hard-iron estimator on simulated fields whose offset is known, and the quaternion
// filter with a magnet riding on a simulated sensor (engine/sim/platform_motion.h,
// engine/sim/magnetic_disturbance.h). Seeds fixed; tolerances stated per test.
#include "engine/attitude/hard_iron_estimator.h"

#include <gtest/gtest.h>

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

// Feeds `seconds` of readings m = R^T m_w + b + noise (0.5 µT) at the true attitude.
HardIronFit FitOver(const AttitudeTrajectory& truth, double seconds, const Eigen::Vector3d& disturbance_uT) {
  HardIronEstimator estimator(20.0, 0.1, 0.1);  // the defaults
  std::mt19937_64 engine(3);
  std::normal_distribution<double> noise(0.0, 0.5);
  Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
  for (int k = 0; k < static_cast<int>(seconds * kRateHz); ++k) {
    const double t_s = k / kRateHz;
    r = truth.At(t_s).toRotationMatrix();
    const Eigen::Vector3d field = t_s > 0.5 * seconds ? kEarthField_uT + disturbance_uT : kEarthField_uT;
    const Eigen::Vector3d m =
        r.transpose() * field + kOffset_uT + Eigen::Vector3d(noise(engine), noise(engine), noise(engine));
    estimator.Add(r, m, 1.0 / kRateHz);
  }
  return estimator.Solve(r);
}

// Turning over the sphere for 30 s: the offset to 0.2 µT (measured 0.05), the world field
// to 0.2 µT, trusted.
TEST(HardIronEstimatorTest, RecoversTheOffsetFromRotation) {
  const HardIronFit fit = FitOver(Tumbling(), 30.0, Eigen::Vector3d::Zero());
  EXPECT_TRUE(fit.trusted);
  EXPECT_GT(fit.diversity, 0.1);
  EXPECT_LT((fit.offset_uT - kOffset_uT).norm(), 0.2);
  EXPECT_LT((fit.field_world_uT - kEarthField_uT).norm(), 0.2);
  EXPECT_LT(fit.residual_uT, 1.0);  // the noise: 0.5 µT per axis, 0.87 µT per sample
}

// Still: the offset and the Earth's field are the same thing to the data.
TEST(HardIronEstimatorTest, NoRotationIsNotTrusted) {
  const HardIronFit fit = FitOver(AttitudeTrajectory::ConstantRate({0.1, 0.2, 0.3}, Eigen::Vector3d::Zero()), 30.0,
                                  Eigen::Vector3d::Zero());
  EXPECT_FALSE(fit.trusted);
  EXPECT_LT(fit.diversity, 1e-6);
}

// The world's field changes by 20 µT halfway (a new room): no constant field and offset
// explain the window, so the residual says so (measured ~9 µT RMS, allowed 5.6).
TEST(HardIronEstimatorTest, AChangedFieldIsNotTrusted) {
  const HardIronFit fit = FitOver(Tumbling(), 30.0, Eigen::Vector3d(20.0, 0.0, 0.0));
  EXPECT_FALSE(fit.trusted);
  EXPECT_GT(fit.residual_uT, 6.0);
}

// A 100 µT magnet on a tumbling sensor from the first sample: the first heading (from the
// offset field) is wrong by tens of degrees; once the sensor has turned, the offset is found
// and the heading follows the corrected field. From 40 s on within 2 degrees (measured
// about 0.5).
TEST(HardIronEstimatorTest, FilterFindsAMagnetPresentFromTheStart) {
  const AttitudeTrajectory truth = Tumbling();
  std::vector<ImuSample> samples = SynthesiseImu(truth, kRateHz, 60.0, ConsumerImuNoise(), 11);
  BodyFixedMagnet magnet;
  magnet.offset_uT = Eigen::Vector3d(60.0, -70.0, 40.0);
  AddBodyFixedMagnet(magnet, &samples);
  AttitudeFilterOptions options;
  options.use_mag = true;
  QuaternionEkf filter(options);
  double first_heading_error_rad = 0.0, late_max_rad = 0.0;
  for (const ImuSample& s : samples) {
    ASSERT_TRUE(filter.Update(s).ok());
    const AttitudeError e = AttitudeErrorOf(filter.estimate().body_to_world, truth.At(s.t_s));
    if (s.t_s == 0.0) first_heading_error_rad = e.heading_rad;
    if (s.t_s >= 40.0) late_max_rad = std::max(late_max_rad, e.total_rad);
  }
  EXPECT_GT(first_heading_error_rad, 20.0 * kDeg);
  EXPECT_TRUE(filter.estimate().mag_calibrated);
  EXPECT_LT((filter.estimate().mag_offset_uT - magnet.offset_uT).norm(), 2.0);
  EXPECT_LT(late_max_rad, 2.0 * kDeg);
}

}  // namespace
}  // namespace localizer::engine
