// PositiveDefinite (covariance_repair.h): an indefinite covariance from rounding is made
// usable and changed by no more than rounding's scale; a usable one is left bit for bit.
#include "engine/core/covariance_repair.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "engine/core/types.h"

namespace localizer::engine {
namespace {

// The eigenvalues of campaign scene 19000190's first reported position covariance:
// -1.4e-5 and 2.2e-5 m^2 across an 18-m far-field range direction (324 m^2).
Mat3 FarFieldStartCovariance() {
  const Mat3 axes = Eigen::AngleAxisd(0.7, Vec3(1.0, 2.0, 0.5).normalized()).toRotationMatrix();
  return axes * Vec3(-1.4302e-5, 2.24413e-5, 323.556).asDiagonal() * axes.transpose();
}

TEST(CovarianceRepair, AnIndefiniteCovarianceBecomesPositiveDefiniteByRoundingsScale) {
  const Mat3 bad = FarFieldStartCovariance();
  ASSERT_NE(Eigen::LLT<Mat3>(bad).info(), Eigen::Success);
  const Mat3 good = PositiveDefinite<3>(bad);
  EXPECT_EQ(Eigen::LLT<Mat3>(good).info(), Eigen::Success);
  const Eigen::SelfAdjointEigenSolver<Mat3> eig(good);
  EXPECT_GT(eig.eigenvalues().minCoeff(), 0.0);
  // Every entry moves by less than a thousandth of the largest variance, and the long
  // direction keeps its variance to a part in a million.
  EXPECT_LT((good - bad).cwiseAbs().maxCoeff(), 1e-3 * 323.556);
  EXPECT_NEAR(eig.eigenvalues().maxCoeff(), 323.556, 323.556 * 1e-5);
}

TEST(CovarianceRepair, APositiveDefiniteCovarianceIsReturnedBitForBit) {
  Mat6 c = Mat6::Identity() * 0.04;
  c(0, 3) = c(3, 0) = 0.039;  // strongly correlated, still positive definite
  c.bottomRightCorner<3, 3>() *= 100.0;
  const Mat6 same = PositiveDefinite<6>(c);
  EXPECT_TRUE((same.array() == c.array()).all());
}

TEST(CovarianceRepair, AZeroVarianceGetsAFloorAndNonFiniteIsLeftForTheCallerToSee) {
  Mat3 c = Mat3::Zero();
  c(0, 0) = 4.0;
  const Mat3 good = PositiveDefinite<3>(c);
  EXPECT_EQ(Eigen::LLT<Mat3>(good).info(), Eigen::Success);
  EXPECT_DOUBLE_EQ(good(0, 0), 4.0);
  Mat3 nan = Mat3::Identity();
  nan(1, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(std::isnan(PositiveDefinite<3>(nan)(1, 1)));
}

}  // namespace
}  // namespace localizer::engine
