#include "engine/array/multilateration.h"

#include <gtest/gtest.h>

#include <random>

namespace localizer::engine {
namespace {

ArrayGeometry Make(std::vector<Vec3> sensors, double c) {
  auto g = ArrayGeometry::Create(std::move(sensors), c);
  EXPECT_TRUE(g.ok()) << g.status().ToString();
  return *g;
}

std::vector<Vec3> Tetrahedron(double edge_m, const Vec3& centre) {
  const double a = edge_m / (2.0 * std::sqrt(2.0));
  return {centre + Vec3(a, a, a), centre + Vec3(a, -a, -a), centre + Vec3(-a, a, -a), centre + Vec3(-a, -a, a)};
}

TEST(Multilateration, ExactOnNoiselessTdoasForManyPositions) {
  const ArrayGeometry six =
      Make({Vec3(0, 0, 0), Vec3(3, 0, 0), Vec3(0, 3, 0), Vec3(0, 0, -3), Vec3(3, 3, -1), Vec3(-2, 1, -2)}, 1500.0);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-15.0, 15.0);
  for (int trial = 0; trial < 50; ++trial) {
    const Vec3 s(u(rng), u(rng), u(rng));
    auto fix = Multilaterate(six, six.Tdoa(s));
    ASSERT_TRUE(fix.ok()) << fix.status().ToString();
    EXPECT_LT((fix->position_m - s).norm(), 1e-6) << "source " << s.transpose();
    EXPECT_LT(fix->rms_residual_s, 1e-12);
  }
}

TEST(Multilateration, FourSensorsExactWithHintResolvingAmbiguity) {
  const ArrayGeometry tetra = Make(Tetrahedron(2.0, Vec3(0, 0, -10)), 1500.0);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-8.0, 8.0);
  for (int trial = 0; trial < 50; ++trial) {
    const Vec3 s = Vec3(u(rng), u(rng), -10.0 + 0.5 * u(rng));
    MultilaterationOptions options;
    options.hint_m = &s;  // a tracker passes its prediction; two exact roots may exist
    auto fix = Multilaterate(tetra, tetra.Tdoa(s), options);
    ASSERT_TRUE(fix.ok());
    EXPECT_LT((fix->position_m - s).norm(), 1e-6) << "source " << s.transpose();
  }
}

TEST(Multilateration, CovarianceMatchesMonteCarloSpread) {
  const ArrayGeometry six =
      Make({Vec3(0, 0, 0), Vec3(3, 0, 0), Vec3(0, 3, 0), Vec3(0, 0, -3), Vec3(3, 3, -1), Vec3(-2, 1, -2)}, 1500.0);
  const Vec3 s(6.0, 4.0, -5.0);
  const double sigma_s = 5e-6;
  const Eigen::VectorXd h = six.Tdoa(s);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0.0, sigma_s);
  const int runs = 2000;
  std::vector<Vec3> fixes;
  MultilaterationOptions options;
  options.tdoa_sigma_s = sigma_s;
  options.hint_m = &s;
  Mat3 predicted = Mat3::Zero();
  for (int i = 0; i < runs; ++i) {
    Eigen::VectorXd d = h;
    for (int p = 0; p < d.size(); ++p) d(p) += noise(rng);
    auto fix = Multilaterate(six, d, options);
    ASSERT_TRUE(fix.ok());
    fixes.push_back(fix->position_m);
    predicted = fix->covariance_m2;
  }
  Vec3 mean = Vec3::Zero();
  for (const Vec3& f : fixes) mean += f;
  mean /= runs;
  Mat3 cov = Mat3::Zero();
  for (const Vec3& f : fixes) cov += (f - mean) * (f - mean).transpose();
  cov /= runs - 1;
  // The sample variance of 2000 draws has a relative standard error of sqrt(2/2000) ~ 3 %;
  // allow 15 % for that and for the linearisation at this noise level.
  for (int axis = 0; axis < 3; ++axis) {
    EXPECT_NEAR(cov(axis, axis), predicted(axis, axis), 0.15 * predicted(axis, axis)) << axis;
  }
  EXPECT_NEAR(std::sqrt(cov.trace()), std::sqrt(predicted.trace()), 0.1 * std::sqrt(predicted.trace()));
  EXPECT_LT((mean - s).norm(), 0.2 * std::sqrt(predicted.trace()));  // nearly unbiased
}

TEST(Multilateration, RejectsWrongSizeAndNonFinite) {
  const ArrayGeometry tetra = Make(Tetrahedron(2.0, Vec3::Zero()), 343.0);
  EXPECT_EQ(Multilaterate(tetra, Eigen::VectorXd::Zero(2)).status().code(), StatusCode::kInvalidArgument);
  Eigen::VectorXd bad = Eigen::VectorXd::Zero(3);
  bad(1) = std::nan("");
  EXPECT_EQ(Multilaterate(tetra, bad).status().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace localizer::engine
