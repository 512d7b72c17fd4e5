// The benchmark's error split on hand-made quaternions with known answers.
#include "engine/attitude/attitude_error.h"

#include <gtest/gtest.h>

#include <cmath>

namespace localizer::engine {
namespace {

Eigen::Quaterniond About(const Eigen::Vector3d& axis, double angle_rad) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle_rad, axis.normalized()));
}

const Eigen::Quaterniond kTruth = About({0.3, -0.5, 0.8}, 1.1);  // any attitude

TEST(AttitudeErrorTest, PureHeadingErrorIsHeadingOnly) {
  const Eigen::Quaterniond estimate = About(Eigen::Vector3d::UnitZ(), 0.2) * kTruth;
  const AttitudeError e = AttitudeErrorOf(estimate, kTruth);
  EXPECT_NEAR(e.total_rad, 0.2, 1e-12);
  EXPECT_NEAR(e.heading_rad, 0.2, 1e-12);
  EXPECT_NEAR(e.inclination_rad, 0.0, 1e-7);  // acos near 1: ~sqrt(eps)
}

TEST(AttitudeErrorTest, PureTiltErrorIsInclinationOnly) {
  const Eigen::Quaterniond estimate = About({1.0, 2.0, 0.0}, 0.05) * kTruth;
  const AttitudeError e = AttitudeErrorOf(estimate, kTruth);
  EXPECT_NEAR(e.total_rad, 0.05, 1e-12);
  EXPECT_NEAR(e.heading_rad, 0.0, 1e-12);
  EXPECT_NEAR(e.inclination_rad, 0.05, 1e-12);
}

TEST(AttitudeErrorTest, SwingTwistSplitOfACombinedError) {
  // Error = heading 30 deg after a 10 deg tilt about East: q_err = Rz(30) Rx(10).
  const double heading = 30.0 * M_PI / 180.0, tilt = 10.0 * M_PI / 180.0;
  const Eigen::Quaterniond error = About(Eigen::Vector3d::UnitZ(), heading) * About(Eigen::Vector3d::UnitX(), tilt);
  const AttitudeError e = AttitudeErrorOf(error * kTruth, kTruth);
  EXPECT_NEAR(e.heading_rad, heading, 1e-12);
  EXPECT_NEAR(e.inclination_rad, tilt, 1e-12);
  // cos(total/2) = cos(heading/2) cos(tilt/2) for this composition.
  EXPECT_NEAR(e.total_rad, 2.0 * std::acos(std::cos(heading / 2) * std::cos(tilt / 2)), 1e-12);
}

TEST(AttitudeErrorTest, SignOfTheQuaternionDoesNotMatter) {
  const Eigen::Quaterniond estimate = About({0.0, 1.0, 1.0}, 0.3) * kTruth;
  const Eigen::Quaterniond negated(-estimate.w(), -estimate.x(), -estimate.y(), -estimate.z());
  const AttitudeError a = AttitudeErrorOf(estimate, kTruth);
  const AttitudeError b = AttitudeErrorOf(negated, kTruth);
  EXPECT_NEAR(a.total_rad, 0.3, 1e-12);
  EXPECT_NEAR(b.total_rad, a.total_rad, 1e-12);
  EXPECT_NEAR(b.heading_rad, a.heading_rad, 1e-12);
  EXPECT_NEAR(b.inclination_rad, a.inclination_rad, 1e-12);
}

TEST(AttitudeErrorTest, HeadingOfAHalfTurnIsPi) {
  const AttitudeError e = AttitudeErrorOf(About(Eigen::Vector3d::UnitZ(), M_PI) * kTruth, kTruth);
  EXPECT_NEAR(e.heading_rad, M_PI, 1e-9);
  EXPECT_NEAR(e.total_rad, M_PI, 1e-6);
}

TEST(AttitudeErrorTest, ScoreIsRmsOverScoredFiniteSamples) {
  const double nan = std::nan("");
  const std::vector<Eigen::Quaterniond> truth = {kTruth, kTruth, kTruth, Eigen::Quaterniond(nan, nan, nan, nan)};
  const std::vector<Eigen::Quaterniond> estimates = {
      About(Eigen::Vector3d::UnitZ(), 0.3) * kTruth,  // scored: heading 0.3
      About(Eigen::Vector3d::UnitX(), 0.4) * kTruth,  // scored: inclination 0.4
      About(Eigen::Vector3d::UnitX(), 2.0) * kTruth,  // not scored (movement 0)
      kTruth};                                        // truth missing: not scored
  const auto score = ScoreAttitude(estimates, truth, {true, true, false, true});
  ASSERT_TRUE(score.ok()) << score.status().ToString();
  EXPECT_EQ(score->count, 2);
  EXPECT_NEAR(score->total_rmse_rad, std::sqrt((0.09 + 0.16) / 2.0), 1e-12);
  EXPECT_NEAR(score->heading_rmse_rad, std::sqrt(0.09 / 2.0), 1e-12);
  EXPECT_NEAR(score->inclination_rmse_rad, std::sqrt(0.16 / 2.0), 1e-7);
}

TEST(AttitudeErrorTest, NonFiniteEstimateScoresAsPi) {
  const double nan = std::nan("");
  const auto score = ScoreAttitude({Eigen::Quaterniond(nan, 0, 0, 0)}, {kTruth}, {true});
  ASSERT_TRUE(score.ok());
  EXPECT_NEAR(score->total_rmse_rad, M_PI, 1e-12);
}

TEST(AttitudeErrorTest, MismatchedLengthsAndNothingScoredAreErrors) {
  EXPECT_EQ(ScoreAttitude({kTruth}, {kTruth, kTruth}, {true, true}).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(ScoreAttitude({kTruth}, {kTruth}, {false}).status().code(), StatusCode::kFailedPrecondition);
}

}  // namespace
}  // namespace localizer::engine
