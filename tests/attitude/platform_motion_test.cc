// The simulator's attitude trajectory and synthetic IMU against first principles.
#include "engine/sim/platform_motion.h"

#include <gtest/gtest.h>

#include <cmath>

namespace localizer::engine {
namespace {

// Body rate from the attitude by a central difference: q(t)^-1 q(t + h) = exp(omega h / 2).
Eigen::Vector3d NumericalBodyRate(const AttitudeTrajectory& trajectory, double t_s) {
  const double h = 1e-5;
  const Eigen::Quaterniond d = trajectory.At(t_s - h).conjugate() * trajectory.At(t_s + h);
  const Eigen::AngleAxisd aa(d);
  return aa.axis() * aa.angle() / (2.0 * h);
}

TEST(PlatformMotionTest, BodyRateIsTheDerivativeOfTheAttitude) {
  AttitudeTrajectoryOptions options;
  options.euler0_rad = {0.1, -0.2, 0.3};
  options.euler_rate_rps = {0.0, 0.0, 0.2};
  options.amplitude_rad = {0.4, 1.8, 0.6};  // pitch passes +-90 degrees
  options.frequency_hz = {0.2, 0.1, 0.05};
  options.phase_rad = {0.3, 0.0, 1.0};
  options.constant_rate_rps = {0.05, 0.1, -0.2};
  const AttitudeTrajectory trajectory(options);
  for (int k = 0; k * 0.37 < 20.0; ++k) {  // 0, 0.37, ..., 19.98 s
    const double t = k * 0.37;
    EXPECT_LT((trajectory.BodyRate(t) - NumericalBodyRate(trajectory, t)).norm(), 1e-6) << t;
  }
}

TEST(PlatformMotionTest, ConstantRateIsAnExponential) {
  const Eigen::Vector3d rate(0.3, -0.2, 0.9);
  const AttitudeTrajectory trajectory = AttitudeTrajectory::ConstantRate({0, 0, 0}, rate);
  const Eigen::Quaterniond expected(Eigen::AngleAxisd(rate.norm() * 2.0, rate.normalized()));
  EXPECT_LT(trajectory.At(2.0).angularDistance(expected), 1e-12);
  EXPECT_LT((trajectory.BodyRate(1.3) - rate).norm(), 1e-12);
}

TEST(PlatformMotionTest, CleanImuReadsGravityAndFieldInTheBody) {
  const AttitudeTrajectory trajectory = AttitudeTrajectory::ConstantRate({0.3, -0.4, 1.0}, {0, 0, 0});
  ImuNoise noise;
  const auto samples = SynthesiseImu(trajectory, 100.0, 1.0, noise, 1);
  ASSERT_EQ(samples.size(), 101u);
  const Eigen::Quaterniond q = trajectory.At(0.5);
  const ImuSample& s = samples[50];
  EXPECT_DOUBLE_EQ(s.t_s, 0.5);
  EXPECT_LT((q * s.accel_mps2 - Eigen::Vector3d(0, 0, 9.81)).norm(), 1e-12);
  EXPECT_LT((q * s.mag_uT - noise.mag_world_uT).norm(), 1e-12);
  EXPECT_LT(s.gyro_rps.norm(), 1e-12);
}

TEST(PlatformMotionTest, NoiseIsSeededAndHasTheStatedSpread) {
  const AttitudeTrajectory trajectory = AttitudeTrajectory::ConstantRate({0, 0, 0}, {0, 0, 0});
  ImuNoise noise;
  noise.gyro_noise_sd_rps = 0.01;
  noise.gyro_bias_rps = {0.1, 0.0, 0.0};
  noise.with_mag = false;
  const auto a = SynthesiseImu(trajectory, 100.0, 100.0, noise, 42);
  const auto b = SynthesiseImu(trajectory, 100.0, 100.0, noise, 42);
  const auto c = SynthesiseImu(trajectory, 100.0, 100.0, noise, 43);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(a[500].gyro_rps, b[500].gyro_rps);
  EXPECT_NE(a[500].gyro_rps, c[500].gyro_rps);
  EXPECT_TRUE(std::isnan(a[0].mag_uT.x()));
  double sum = 0.0, sum2 = 0.0;
  for (const ImuSample& s : a) {
    sum += s.gyro_rps.x();
    sum2 += (s.gyro_rps.x() - 0.1) * (s.gyro_rps.x() - 0.1);
  }
  const double n = static_cast<double>(a.size());
  EXPECT_NEAR(sum / n, 0.1, 4.0 * 0.01 / std::sqrt(n));
  EXPECT_NEAR(std::sqrt(sum2 / n), 0.01, 0.0005);  // 10001 draws: std of the std ~0.7 %
}

TEST(PlatformMotionTest, LinearAccelerationAndDisturbanceAppearInTheReadings) {
  AttitudeTrajectoryOptions options;
  options.linear_amplitude_mps2 = {2.0, 0.0, 0.0};
  options.linear_frequency_hz = 0.25;
  ImuNoise noise;
  noise.mag_disturbance_world_uT = {10.0, 0.0, 0.0};
  noise.disturbance_start_s = 1.0;
  noise.disturbance_end_s = 2.0;
  const auto samples = SynthesiseImu(AttitudeTrajectory(options), 10.0, 3.0, noise, 1);
  EXPECT_NEAR(samples[10].accel_mps2.x(), 2.0, 1e-12);  // t = 1 s: sin(pi / 2)
  EXPECT_NEAR(samples[15].mag_uT.x(), 10.0, 1e-12);
  EXPECT_NEAR(samples[25].mag_uT.x(), 0.0, 1e-12);
}

TEST(PlatformMotionTest, EmptyForNonPositiveRateOrDuration) {
  const AttitudeTrajectory trajectory = AttitudeTrajectory::ConstantRate({0, 0, 0}, {0, 0, 0});
  EXPECT_TRUE(SynthesiseImu(trajectory, 0.0, 1.0, ImuNoise{}, 1).empty());
  EXPECT_TRUE(SynthesiseImu(trajectory, 100.0, -1.0, ImuNoise{}, 1).empty());
}

}  // namespace
}  // namespace localizer::engine
