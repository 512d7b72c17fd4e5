// The quaternion MEKF on simulated motion whose attitude is known exactly
// (engine/sim/platform_motion.h). Seeds fixed; tolerances stated per test.
#include "engine/attitude/quaternion_ekf.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "engine/attitude/attitude_math.h"
#include "tests/attitude/attitude_test_util.h"

namespace localizer::engine {
namespace {

using testing::ConsumerImuNoise;
using testing::kDeg;
using testing::RunFilter;
using testing::ThroughNinetyDegreesPitch;

AttitudeFilterOptions Defaults(bool use_mag) {
  AttitudeFilterOptions options;
  options.use_mag = use_mag;
  return options;
}

// A clean IMU gives the attitude to rounding: integration of a constant rate is exact
// (exponential map), and the accelerometer and magnetometer agree with it exactly.
TEST(QuaternionEkfTest, StaticAttitudeIsExact) {
  const AttitudeTrajectory truth = AttitudeTrajectory::ConstantRate({0.4, -0.3, 1.2}, {0, 0, 0});
  const auto samples = SynthesiseImu(truth, 200.0, 5.0, ImuNoise{}, 1);
  const auto errors = RunFilter(Defaults(true), truth, samples);
  EXPECT_LT(errors.max_total_rad, 1e-6);
  const auto six_d = RunFilter(Defaults(false), truth, samples);
  EXPECT_LT(six_d.max_inclination_rad, 1e-6);
  EXPECT_TRUE(six_d.last.at_rest);
}

TEST(QuaternionEkfTest, ConstantRateRotationIsExact) {
  const AttitudeTrajectory truth = AttitudeTrajectory::ConstantRate({0.2, 0.1, -0.5}, {0.3, -0.2, 0.9});
  const auto samples = SynthesiseImu(truth, 200.0, 20.0, ImuNoise{}, 2);
  EXPECT_LT(RunFilter(Defaults(true), truth, samples).max_total_rad, 1e-6);
  EXPECT_LT(RunFilter(Defaults(false), truth, samples).max_inclination_rad, 1e-6);
}

// With realistic noise (BROAD-like: gyro 0.005 rad/s, accel 0.05 m/s^2, mag 0.5 µT per
// sample at 200 Hz, a gyro bias of 0.2 deg/s, no rest to learn it) inclination stays within
// a degree and the total error within 2.5 degrees once settled (measured: 0.5 and 1.9; the
// first sample alone fixes heading to ~2 deg: 0.5 µT of noise on 17 µT horizontal, and the
// heading bias is learnt from the magnetometer over tens of seconds).
TEST(QuaternionEkfTest, NoisySinusoidalMotionWithinOneDegree) {
  AttitudeTrajectoryOptions motion;
  motion.amplitude_rad = {0.6, 0.5, 1.5};
  motion.frequency_hz = {0.13, 0.07, 0.05};
  const AttitudeTrajectory truth(motion);
  ImuNoise noise;
  noise.gyro_noise_sd_rps = 0.005;
  noise.gyro_bias_rps = {0.003, -0.002, 0.004};
  noise.accel_noise_sd_mps2 = 0.05;
  noise.mag_noise_sd_uT = 0.5;
  const auto samples = SynthesiseImu(truth, 200.0, 60.0, noise, 3);
  const auto nine_d = RunFilter(Defaults(true), truth, samples, 5.0);
  EXPECT_LT(nine_d.max_total_rad, 2.5 * kDeg);
  EXPECT_LT(nine_d.max_inclination_rad, 1.0 * kDeg);
  const auto six_d = RunFilter(Defaults(false), truth, samples, 5.0);
  EXPECT_LT(six_d.max_inclination_rad, 1.0 * kDeg);
}

// Pitch passes +-90 degrees (amplitude 1.8 rad): the quaternion filter does not notice.
TEST(QuaternionEkfTest, PassesThroughNinetyDegreesPitch) {
  const AttitudeTrajectory truth = ThroughNinetyDegreesPitch();
  const ImuNoise noise = ConsumerImuNoise();
  const auto samples = SynthesiseImu(truth, 200.0, 30.0, noise, 4);
  double max_pitch = 0.0;  // settled after 2 s, pitch first reaches 90 deg at 2.5 s
  for (const ImuSample& s : samples) {
    max_pitch = std::max(max_pitch, std::abs(EulerFromQuaternion(truth.At(s.t_s)).y()));
  }
  ASSERT_GT(max_pitch, 89.5 * kDeg);  // the trajectory does reach the singularity
  EXPECT_LT(RunFilter(Defaults(true), truth, samples, 2.0).max_total_rad, 1.0 * kDeg);
  EXPECT_LT(RunFilter(Defaults(false), truth, samples, 2.0).max_inclination_rad, 1.0 * kDeg);
}

// Standing still with a gyro bias of about 1 deg/s: rest detection measures it. Heading
// bias (z) is seen by nothing else without the magnetometer.
TEST(QuaternionEkfTest, RecoversGyroBiasAtRest) {
  const AttitudeTrajectory truth = AttitudeTrajectory::ConstantRate({0.1, -0.2, 0.0}, {0, 0, 0});
  ImuNoise noise;
  noise.gyro_noise_sd_rps = 0.002;
  noise.gyro_bias_rps = {0.01, -0.015, 0.012};
  noise.accel_noise_sd_mps2 = 0.03;
  noise.with_mag = false;
  const auto samples = SynthesiseImu(truth, 200.0, 20.0, noise, 5);
  const auto run = RunFilter(Defaults(false), truth, samples);
  EXPECT_TRUE(run.last.at_rest);
  EXPECT_LT((run.last.gyro_bias_rps - noise.gyro_bias_rps).cwiseAbs().maxCoeff(), 1e-3);
  // Without rest detection the heading bias stays unknown.
  AttitudeFilterOptions no_rest = Defaults(false);
  no_rest.rest_min_s = 0.0;
  const auto blind = RunFilter(no_rest, truth, samples);
  EXPECT_GT(std::abs(blind.last.gyro_bias_rps.z() - noise.gyro_bias_rps.z()), 5e-3);
  EXPECT_GT(blind.max_heading_rad, 5.0 * kDeg);
  EXPECT_LT(run.max_heading_rad, 1.0 * kDeg);
}

// The platform shakes (world-frame linear acceleration of 4 m/s^2 on East and Up at
// 0.7 Hz) while level and still in attitude: the raw accelerometer direction swings by up
// to ~20 degrees. Defaults stay within a degree once the start has passed; a filter that
// believes every sample does not. The shaking starts at t = 0 as sin(0), which is a velocity
// step of 0.9 m/s: the world-frame low-pass carries that step for a few seconds. With two
// stages (accel_lowpass_order 2, the default since issue 22) the largest error is 1.68 deg
// from 2 s (one stage: 1.33) and 0.92 deg from 5 s (one stage: 1.26).
TEST(QuaternionEkfTest, RejectsLinearAcceleration) {
  AttitudeTrajectoryOptions motion;
  motion.amplitude_rad = {0.2, 0.1, 0.0};
  motion.frequency_hz = {0.05, 0.03, 0.0};
  motion.linear_amplitude_mps2 = {4.0, 0.0, 4.0};
  motion.linear_frequency_hz = 0.7;
  const AttitudeTrajectory truth(motion);
  ImuNoise noise;
  noise.gyro_noise_sd_rps = 0.005;
  noise.accel_noise_sd_mps2 = 0.05;
  noise.with_mag = false;
  const auto samples = SynthesiseImu(truth, 200.0, 30.0, noise, 6);
  EXPECT_LT(RunFilter(Defaults(false), truth, samples, 2.0).max_inclination_rad, 2.0 * kDeg);
  EXPECT_LT(RunFilter(Defaults(false), truth, samples, 5.0).max_inclination_rad, 1.0 * kDeg);
  AttitudeFilterOptions naive = Defaults(false);
  naive.accel_lowpass_s = 0.0;
  naive.accel_reject_mps2 = 1e3;
  naive.accel_noise_gain = 0.0;
  naive.accel_tilt_sd_rad = 0.05;
  EXPECT_GT(RunFilter(naive, truth, samples, 2.0).max_inclination_rad, 3.0 * kDeg);
}

// The norm test alone (no low-pass): a sample whose |f| departs from g by more than
// accel_reject_mps2 is not used.
TEST(QuaternionEkfTest, AccelNormRejectionSkipsTheUpdate) {
  AttitudeFilterOptions options = Defaults(false);
  options.accel_lowpass_s = 0.0;
  auto filter = CreateAttitudeFilter(options);
  ASSERT_TRUE(filter.ok());
  ImuSample s;
  s.accel_mps2 = {0.0, 0.0, 9.81};
  ASSERT_TRUE((*filter)->Update(s).ok());
  s.t_s = 0.01;
  ASSERT_TRUE((*filter)->Update(s).ok());
  EXPECT_TRUE((*filter)->estimate().accel_used);
  s.t_s = 0.02;
  s.accel_mps2 = {3.0, 0.0, 12.0};  // |f| = 12.4: 2.6 m/s^2 from g
  ASSERT_TRUE((*filter)->Update(s).ok());
  EXPECT_FALSE((*filter)->estimate().accel_used);
  EXPECT_LT(AttitudeErrorOf((*filter)->estimate().body_to_world, Eigen::Quaterniond::Identity()).inclination_rad, 1e-9);
}

// A magnetic disturbance fixed in the world, from 5 s to 15 s, turning the field's
// horizontal part: by its norm (+17 %) in one case, by its dip (-15 deg at an unchanged
// norm) in the other. Both would pull heading by tens of degrees; the filter drops them and
// dead-reckons heading on the gyro for those 10 s (measured drift 2.1 deg, bound 3).
class MagDisturbanceTest : public ::testing::TestWithParam<Eigen::Vector3d> {};

TEST_P(MagDisturbanceTest, RejectsDisturbedField) {
  AttitudeTrajectoryOptions motion;
  motion.amplitude_rad = {0.2, 0.15, 0.4};
  motion.frequency_hz = {0.11, 0.07, 0.05};
  const AttitudeTrajectory truth(motion);
  ImuNoise noise = ConsumerImuNoise();
  noise.mag_disturbance_world_uT = GetParam();
  noise.disturbance_start_s = 5.0;
  noise.disturbance_end_s = 15.0;
  const auto samples = SynthesiseImu(truth, 200.0, 20.0, noise, 7);
  const auto guarded = RunFilter(Defaults(true), truth, samples, 2.0);
  EXPECT_LT(guarded.max_heading_rad, 3.0 * kDeg);
  EXPECT_LT(guarded.max_inclination_rad, 1.0 * kDeg);
  AttitudeFilterOptions trusting = Defaults(true);
  trusting.mag_norm_tolerance = 10.0;
  trusting.mag_dip_tolerance_rad = 10.0;
  trusting.mag_heading_gate_rad = 10.0;  // and no heading-consistency gate (alone it keeps this to ~9 deg)
  const auto fooled = RunFilter(trusting, truth, samples, 2.0);
  EXPECT_GT(fooled.max_heading_rad, 10.0 * kDeg);
}

INSTANTIATE_TEST_SUITE_P(NormAndDip, MagDisturbanceTest,
                         ::testing::Values(Eigen::Vector3d(25.0, 0.0, 0.0),    // norm +17 %
                                           Eigen::Vector3d(12.0, 8.0, 6.0)));  // dip -15 deg

TEST(QuaternionEkfTest, BadSamplesAreErrorsAndLeaveTheStateAlone) {
  auto filter = CreateAttitudeFilter(Defaults(true));
  ASSERT_TRUE(filter.ok());
  ImuSample s;
  s.t_s = 1.0;
  s.accel_mps2 = {0.0, 0.0, 9.81};
  s.mag_uT = {0.0, 17.0, -46.0};
  ASSERT_TRUE((*filter)->Update(s).ok());
  const AttitudeEstimate before = (*filter)->estimate();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  ImuSample bad = s;
  bad.t_s = 0.5;  // out of order
  EXPECT_EQ((*filter)->Update(bad).code(), StatusCode::kInvalidArgument);
  bad.t_s = 1.0;  // repeated
  EXPECT_EQ((*filter)->Update(bad).code(), StatusCode::kInvalidArgument);
  bad = s;
  bad.t_s = 1.01;
  bad.gyro_rps.y() = nan;
  EXPECT_EQ((*filter)->Update(bad).code(), StatusCode::kInvalidArgument);
  bad.gyro_rps.y() = 0.0;
  bad.accel_mps2.x() = std::numeric_limits<double>::infinity();
  EXPECT_EQ((*filter)->Update(bad).code(), StatusCode::kInvalidArgument);
  bad.accel_mps2.x() = 0.0;
  bad.t_s = nan;
  EXPECT_EQ((*filter)->Update(bad).code(), StatusCode::kInvalidArgument);
  const AttitudeEstimate after = (*filter)->estimate();
  EXPECT_EQ(after.t_s, before.t_s);
  EXPECT_TRUE(after.body_to_world.coeffs().isApprox(before.body_to_world.coeffs()));
  // A missing magnetometer value is not an error: no mag update for that sample.
  ImuSample no_mag = s;
  no_mag.t_s = 1.02;
  no_mag.mag_uT.setConstant(nan);
  EXPECT_TRUE((*filter)->Update(no_mag).ok());
  EXPECT_FALSE((*filter)->estimate().mag_used);
  EXPECT_TRUE((*filter)->estimate().body_to_world.coeffs().allFinite());
}

TEST(QuaternionEkfTest, OptionsAreValidated) {
  AttitudeFilterOptions options;
  options.accel_tilt_sd_rad = 0.0;
  EXPECT_EQ(CreateAttitudeFilter(options).status().code(), StatusCode::kInvalidArgument);
  options = AttitudeFilterOptions{};
  options.gyro_noise_rps_rthz = std::numeric_limits<double>::quiet_NaN();
  const auto result = CreateAttitudeFilter(options);
  ASSERT_FALSE(result.ok());
  EXPECT_NE(result.status().message().find("gyro_noise_rps_rthz"), std::string::npos);
  EXPECT_EQ(ParseAttitudeFilterKind("kalman").status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(*ParseAttitudeFilterKind("euler"), AttitudeFilterKind::kEuler);
}

// The reported std of the error angles is honest: on the noisy run the actual
// inclination error stays within 4 sigma of the reported world East/North stds.
TEST(QuaternionEkfTest, ReportedStdCoversTheError) {
  AttitudeTrajectoryOptions motion;
  motion.amplitude_rad = {0.4, 0.3, 0.8};
  motion.frequency_hz = {0.1, 0.08, 0.05};
  const AttitudeTrajectory truth(motion);
  const ImuNoise noise = ConsumerImuNoise();
  const auto samples = SynthesiseImu(truth, 200.0, 30.0, noise, 8);
  auto filter = CreateAttitudeFilter(Defaults(true));
  ASSERT_TRUE(filter.ok());
  int outside = 0, counted = 0;
  for (const ImuSample& s : samples) {
    ASSERT_TRUE((*filter)->Update(s).ok());
    if (s.t_s < 2.0) continue;
    const AttitudeEstimate e = (*filter)->estimate();
    const double sd = e.world_error_sd_rad.head<2>().norm();
    ASSERT_GT(sd, 0.0);
    ++counted;
    if (AttitudeErrorOf(e.body_to_world, truth.At(s.t_s)).inclination_rad > 4.0 * sd) ++outside;
  }
  EXPECT_LT(outside, counted / 100);
}

}  // namespace
}  // namespace localizer::engine
