// Converted measurements: the unbiased conversion removes the naive one's bias at large
// bearing noise, and its covariance is consistent (NEES ~ dim z) where the naive one's is
// not. Seeded Monte Carlo against the geometry's truth.
#include "engine/tws/polar_conversion.h"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>
#include <random>

namespace localizer::engine::tws {
namespace {

struct Stats {
  Eigen::Vector3d mean_error = Eigen::Vector3d::Zero();
  double error_std = 0.0;  // per-draw std of the error along its largest axis
  double nees = 0.0;
};

Stats Draw(bool spherical, Conversion method, const PolarNoise& noise, double r, double theta, double phi, int draws,
           uint64_t seed) {
  std::mt19937_64 engine(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  const Eigen::Vector3d truth =
      spherical ? r * Eigen::Vector3d(std::cos(phi) * std::cos(theta), std::cos(phi) * std::sin(theta), std::sin(phi))
                : r * Eigen::Vector3d(std::cos(theta), std::sin(theta), 0.0);
  Stats s;
  Eigen::Vector3d sum_sq = Eigen::Vector3d::Zero();
  for (int i = 0; i < draws; ++i) {
    const double rm = r + noise.range_sigma_m * n(engine);
    const double tm = theta + noise.bearing_sigma_rad * n(engine);
    const double pm = phi + noise.elevation_sigma_rad * n(engine);
    if (spherical) {
      const Converted3 c = ConvertSpherical(rm, tm, pm, noise, method);
      const Eigen::Vector3d e = c.position_m - truth;
      s.mean_error += e;
      sum_sq += e.cwiseAbs2();
      s.nees += e.dot(c.covariance_m2.inverse() * e);
    } else {
      const Converted2 c = ConvertPolar(rm, tm, noise, method);
      const Eigen::Vector2d e = c.position_m - truth.head<2>();
      s.mean_error.head<2>() += e;
      sum_sq.head<2>() += e.cwiseAbs2();
      s.nees += e.dot(c.covariance_m2.inverse() * e);
    }
  }
  s.mean_error /= draws;
  s.error_std = std::sqrt(sum_sq.maxCoeff() / draws);
  s.nees /= draws;
  return s;
}

TEST(PolarConversion, UnbiasedRemovesTheNaiveBiasAtLargeBearingNoise) {
  // 10 km, bearing std 0.15 rad (8.6 deg), range std 10 m: the naive conversion pulls the
  // mean towards the sensor by r (1 - exp(-sigma^2 / 2)) = 112 m.
  PolarNoise noise{10.0, 0.15, 0.0};
  const int draws = 200000;
  const double r = 10000.0, theta = 0.6;
  const Stats naive = Draw(false, Conversion::kNaive, noise, r, theta, 0.0, draws, 11);
  const Stats unbiased = Draw(false, Conversion::kUnbiased, noise, r, theta, 0.0, draws, 11);
  const double standard_error = unbiased.error_std / std::sqrt(draws);  // ~3.4 m
  const double theory = r * (1.0 - std::exp(-0.5 * noise.bearing_sigma_rad * noise.bearing_sigma_rad));
  EXPECT_NEAR(naive.mean_error.norm(), theory, 5.0 * standard_error);
  EXPECT_LT(unbiased.mean_error.norm(), 4.0 * standard_error);
  EXPECT_LT(unbiased.mean_error.norm(), naive.mean_error.norm() / 5.0);
}

TEST(PolarConversion, UnbiasedCovarianceIsConsistentNaiveIsNot) {
  const int draws = 100000;
  for (double sigma : {0.01, 0.1, 0.3}) {
    PolarNoise noise{10.0, sigma, 0.0};
    const Stats unbiased = Draw(false, Conversion::kUnbiased, noise, 10000.0, 2.0, 0.0, draws, 5);
    EXPECT_NEAR(unbiased.nees, 2.0, 0.1) << "bearing std " << sigma;
  }
  // At 0.3 rad (17 deg) the naive covariance no longer describes its error.
  PolarNoise wide{10.0, 0.3, 0.0};
  const Stats naive = Draw(false, Conversion::kNaive, wide, 10000.0, 2.0, 0.0, draws, 5);
  EXPECT_GT(std::abs(naive.nees - 2.0), 0.3) << naive.nees;
}

TEST(PolarConversion, SphericalUnbiasedAndConsistent) {
  PolarNoise noise{10.0, 0.1, 0.1};
  const int draws = 200000;
  const double r = 8000.0, theta = -1.0, phi = 0.4;
  const Stats naive = Draw(true, Conversion::kNaive, noise, r, theta, phi, draws, 3);
  const Stats unbiased = Draw(true, Conversion::kUnbiased, noise, r, theta, phi, draws, 3);
  const double standard_error = unbiased.error_std / std::sqrt(draws);
  EXPECT_LT(unbiased.mean_error.norm(), 4.0 * standard_error);
  EXPECT_GT(naive.mean_error.norm(), 5.0 * unbiased.mean_error.norm() + 10.0 * standard_error);
  EXPECT_NEAR(unbiased.nees, 3.0, 0.15);
}

TEST(PolarConversion, SmallNoiseConversionsAgree) {
  PolarNoise noise{10.0, 0.001, 0.001};
  const Converted2 a = ConvertPolar(5000.0, 1.0, noise, Conversion::kNaive);
  const Converted2 b = ConvertPolar(5000.0, 1.0, noise, Conversion::kUnbiased);
  EXPECT_LT((a.position_m - b.position_m).norm(), 0.01);
  EXPECT_LT((a.covariance_m2 - b.covariance_m2).norm(), 0.01 * a.covariance_m2.norm());
  // The 2-D form equals the spherical one at zero elevation and elevation noise.
  PolarNoise flat{10.0, 0.2, 0.0};
  const Converted2 p = ConvertPolar(5000.0, 1.0, flat, Conversion::kUnbiased);
  const Converted3 s = ConvertSpherical(5000.0, 1.0, 0.0, flat, Conversion::kUnbiased);
  EXPECT_LT((p.position_m - s.position_m.head<2>()).norm(), 1e-9);
  EXPECT_LT((p.covariance_m2 - s.covariance_m2.topLeftCorner<2, 2>()).norm(), 1e-6);
}

}  // namespace
}  // namespace localizer::engine::tws
