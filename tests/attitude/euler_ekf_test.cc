// The seed's Euler-angle EKF: exact on clean data, agrees with the quaternion filter away
// from +-90 degrees pitch, and degrades there (the reason the quaternion filter is default).
#include "engine/attitude/euler_ekf.h"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/attitude/attitude_test_util.h"

namespace localizer::engine {
namespace {

using testing::ConsumerImuNoise;
using testing::kDeg;
using testing::RunFilter;
using testing::ThroughNinetyDegreesPitch;

AttitudeFilterOptions Euler(bool use_mag) {
  AttitudeFilterOptions options;
  options.kind = AttitudeFilterKind::kEuler;
  options.use_mag = use_mag;
  return options;
}

TEST(EulerEkfTest, StaticAttitudeIsExact) {
  const AttitudeTrajectory truth = AttitudeTrajectory::ConstantRate({0.4, -0.3, 1.2}, {0, 0, 0});
  const auto samples = SynthesiseImu(truth, 200.0, 5.0, ImuNoise{}, 11);
  EXPECT_LT(RunFilter(Euler(true), truth, samples).max_total_rad, 1e-6);
}

// Explicit Euler integration of the Euler-angle rates is first order: a constant body rate
// of 0.5 rad/s at 1 kHz leaves an error of order (rate dt)^2 per step, held down by the
// accelerometer and magnetometer; 0.1 degree is the stated bound.
TEST(EulerEkfTest, ConstantRateRotationWithinATenthOfADegree) {
  const AttitudeTrajectory truth = AttitudeTrajectory::ConstantRate({0.2, 0.1, -0.5}, {0.1, -0.1, 0.5});
  const auto samples = SynthesiseImu(truth, 1000.0, 10.0, ImuNoise{}, 12);
  EXPECT_LT(RunFilter(Euler(true), truth, samples).max_total_rad, 0.1 * kDeg);
}

TEST(EulerEkfTest, AgreesWithQuaternionFilterAwayFromNinetyDegrees) {
  AttitudeTrajectoryOptions motion;
  motion.amplitude_rad = {0.5, 0.4, 1.0};
  motion.frequency_hz = {0.13, 0.07, 0.05};
  const AttitudeTrajectory truth(motion);
  ImuNoise noise;  // no gyro bias: the Euler EKF does not estimate it
  noise.gyro_noise_sd_rps = 0.005;
  noise.accel_noise_sd_mps2 = 0.05;
  noise.mag_noise_sd_uT = 0.5;
  const auto samples = SynthesiseImu(truth, 200.0, 40.0, noise, 13);
  auto euler = CreateAttitudeFilter(Euler(true));
  AttitudeFilterOptions q_options;
  q_options.use_mag = true;
  auto quaternion = CreateAttitudeFilter(q_options);
  ASSERT_TRUE(euler.ok() && quaternion.ok());
  double max_difference = 0.0;
  for (const ImuSample& s : samples) {
    ASSERT_TRUE((*euler)->Update(s).ok());
    ASSERT_TRUE((*quaternion)->Update(s).ok());
    if (s.t_s < 2.0) continue;
    max_difference = std::max(
        max_difference,
        AttitudeErrorOf((*euler)->estimate().body_to_world, (*quaternion)->estimate().body_to_world).total_rad);
  }
  EXPECT_LT(max_difference, 1.5 * kDeg);
  EXPECT_LT(RunFilter(Euler(true), truth, samples, 2.0).max_total_rad, 1.5 * kDeg);
}

// Pitch through +-90 degrees: tan(pitch) and 1/cos(pitch) blow up in the propagation and the
// accelerometer's roll is undefined there; the Euler EKF loses the attitude, the quaternion
// filter (quaternion_ekf_test) stays within a degree on the same motion.
TEST(EulerEkfTest, DegradesThroughNinetyDegreesPitch) {
  const AttitudeTrajectory truth = ThroughNinetyDegreesPitch();
  const ImuNoise noise = ConsumerImuNoise();
  const auto samples = SynthesiseImu(truth, 200.0, 30.0, noise, 4);
  const auto euler = RunFilter(Euler(true), truth, samples, 2.0);
  AttitudeFilterOptions q_options;
  q_options.use_mag = true;
  const auto quaternion = RunFilter(q_options, truth, samples, 2.0);
  std::printf("through 90 deg pitch: max total error euler %.2f deg, quaternion %.3f deg\n", euler.max_total_rad / kDeg,
              quaternion.max_total_rad / kDeg);
  EXPECT_GT(euler.max_total_rad, 5.0 * kDeg);
  EXPECT_LT(quaternion.max_total_rad, 1.0 * kDeg);
  EXPECT_TRUE(euler.last.body_to_world.coeffs().allFinite());  // degraded, not broken
}

TEST(EulerEkfTest, BadSamplesAreErrors) {
  auto filter = CreateAttitudeFilter(Euler(false));
  ASSERT_TRUE(filter.ok());
  ImuSample s;
  s.accel_mps2 = {0.0, 0.0, 9.81};
  ASSERT_TRUE((*filter)->Update(s).ok());
  EXPECT_EQ((*filter)->Update(s).code(), StatusCode::kInvalidArgument);  // same t_s
  s.t_s = 0.01;
  s.gyro_rps.x() = std::nan("");
  EXPECT_EQ((*filter)->Update(s).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ((*filter)->estimate().t_s, 0.0);
}

}  // namespace
}  // namespace localizer::engine
