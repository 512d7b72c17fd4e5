#include "engine/experiments/mixture_noise.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "tests/sim/npy_reader.h"

namespace localizer::engine::experiments {
namespace {

constexpr char kNolanCdfTable[] =
    "/usr/lib/python3/dist-packages/scipy/stats/tests/data/levy_stable/"
    "stable-Z1-cdf-sample-data.npy";
constexpr int kSamples = 200000;  // 2-D vectors: 400000 axis draws
constexpr double kSigmas = 4.5;
constexpr double kTableRounding = 1e-3;  // the table's x are printed to ~7 digits

std::vector<double> AxisDraws(const MixtureNoise& noise, uint64_t seed) {
  std::mt19937_64 engine(seed);
  std::vector<double> draws;
  draws.reserve(2 * kSamples);
  for (int i = 0; i < kSamples; ++i) {
    const Eigen::Vector2d n = SampleMixtureNoise(noise, engine);
    draws.push_back(n.x());
    draws.push_back(n.y());
  }
  std::sort(draws.begin(), draws.end());
  return draws;
}

double Ecdf(const std::vector<double>& sorted, double x) {
  return static_cast<double>(std::upper_bound(sorted.begin(), sorted.end(), x) - sorted.begin()) /
         static_cast<double>(sorted.size());
}

double NormalCdf(double z) { return 0.5 * std::erfc(-z / std::numbers::sqrt2); }

TEST(MixtureNoise, EmpiricalCdfIsTheMixtureOfGaussianAndNolanS1) {
  StatusOr<testing::NpyMatrix> table = testing::ReadNpyMatrix(kNolanCdfTable);
  ASSERT_TRUE(table.ok()) << table.status().ToString() << " (install python3-scipy)";
  const MixtureNoise noise;  // e 0.5, sigma 1 m, S1(1.7, 1, 10 m, -3 m)
  const std::vector<double> draws = AxisDraws(noise, 11);
  int checked = 0;
  for (int64_t r = 0; r < table->rows; ++r) {
    if (std::abs(table->at(r, 2) - 1.7) > 1e-9 || table->at(r, 3) != 1.0) continue;
    // The stable part's percentile point, in metres, and the mixture's CDF there.
    const double x = noise.stable.scale * table->at(r, 0) + noise.stable.location;
    const double e = noise.gaussian_probability;
    const double p = e * NormalCdf(x / noise.gaussian_sigma_m) + (1.0 - e) * table->at(r, 1);
    const double tolerance = kSigmas * std::sqrt(p * (1.0 - p) / static_cast<double>(draws.size())) + kTableRounding;
    EXPECT_NEAR(Ecdf(draws, x), p, tolerance) << "x " << x;
    ++checked;
  }
  EXPECT_EQ(checked, 11);
  // Near 0 the Gaussian half dominates: half the draws within +-1 sigma of the Gaussian
  // alone would give 0.34; the stable part adds (1 - e) P(|S| < 1 m), about 0.02.
  const double within = Ecdf(draws, 1.0) - Ecdf(draws, -1.0);
  EXPECT_GT(within, 0.5 * 0.6827);
  EXPECT_LT(within, 0.5 * 0.6827 + 0.5 * 0.06);
}

TEST(MixtureNoise, ProbabilityOneIsPurelyGaussianAndZeroPurelyStable) {
  MixtureNoise gaussian;
  gaussian.gaussian_probability = 1.0;
  gaussian.gaussian_sigma_m = 2.0;
  const std::vector<double> g = AxisDraws(gaussian, 12);
  double squares = 0.0;
  for (double v : g) squares += v * v;
  EXPECT_NEAR(std::sqrt(squares / static_cast<double>(g.size())), 2.0,
              0.02);  // 1 %: ~6 standard errors
  EXPECT_LT(g.back(), 2.0 * 6.0);

  MixtureNoise stable;
  stable.gaussian_probability = 0.0;
  const std::vector<double> s = AxisDraws(stable, 13);
  // Median of S1(1.7, 1, 10, -3): 10 * -0.331145 - 3 (Nolan's table), standard error ~0.05.
  EXPECT_NEAR(s[s.size() / 2], -6.31145, 0.25);
  EXPECT_GT(s.back(), 1000.0);  // the heavy right tail shows in 400000 draws
}

TEST(MixtureNoise, AxesChooseTheirComponentIndependently) {
  const MixtureNoise noise;
  std::mt19937_64 engine(14);
  int x_near = 0, y_near = 0, both_near = 0;
  for (int i = 0; i < kSamples; ++i) {
    const Eigen::Vector2d n = SampleMixtureNoise(noise, engine);
    const bool x = std::abs(n.x()) < 2.0, y = std::abs(n.y()) < 2.0;
    x_near += x;
    y_near += y;
    both_near += x && y;
  }
  const double px = static_cast<double>(x_near) / kSamples, py = static_cast<double>(y_near) / kSamples;
  const double p_both = static_cast<double>(both_near) / kSamples;
  // One shared choice would give P(both) ~ 0.5 * 0.95 = 0.48; independent ones ~ 0.25.
  EXPECT_NEAR(p_both, px * py, kSigmas * std::sqrt(px * py / kSamples) + 0.005);
}

TEST(MixtureNoise, SameSeedSameDraws) {
  const MixtureNoise noise;
  std::mt19937_64 a(99), b(99);
  for (int i = 0; i < 1000; ++i) {
    const Eigen::Vector2d na = SampleMixtureNoise(noise, a), nb = SampleMixtureNoise(noise, b);
    ASSERT_EQ(na.x(), nb.x());
    ASSERT_EQ(na.y(), nb.y());
  }
}

TEST(MixtureDensity, IsTheWeightedSumOfItsComponentsAndIntegratesToOne) {
  const MixtureNoise noise;
  StatusOr<MixtureDensity> density = MixtureDensity::Create(noise);
  ASSERT_TRUE(density.ok()) << density.status().ToString();
  StatusOr<StableDensityTable> stable = StableDensityTable::Create(noise.stable);
  ASSERT_TRUE(stable.ok());
  for (const double n : {-40.0, -8.1, -1.0, 0.0, 0.5, 3.0, 250.0}) {
    const double gaussian = std::exp(-0.5 * n * n) / std::sqrt(2.0 * std::numbers::pi);
    const double expected = std::log(0.5 * gaussian + 0.5 * std::exp(stable->LogDensity(n)));
    EXPECT_NEAR(density->LogDensity(n), expected, 1e-12) << n;
  }
  // Midpoint rule: 5 mm steps where the Gaussian lives, 0.5 m beyond 100 m (the stable
  // part's scale is 10 m). Beyond 20 km the right tail holds 0.5 * 2 C 2000^-1.7 ~ 3e-7.
  const auto mass_over = [&](double lo, double hi, double h) {
    double sum = 0.0;
    for (int k = 0; lo + (k + 0.5) * h < hi; ++k) sum += std::exp(density->LogDensity(lo + (k + 0.5) * h)) * h;
    return sum;
  };
  const double mass =
      mass_over(-20000.0, -100.0, 0.5) + mass_over(-100.0, 100.0, 0.005) + mass_over(100.0, 20000.0, 0.5);
  EXPECT_NEAR(mass, 1.0, 1e-4);
  EXPECT_NEAR(density->LogDensity(Eigen::Vector2d(0.3, -2.0)), density->LogDensity(0.3) + density->LogDensity(-2.0),
              1e-15);
}

TEST(MixtureDensity, RejectsBadOptionsNamingTheField) {
  MixtureNoise noise;
  noise.gaussian_probability = 1.5;
  StatusOr<MixtureDensity> density = MixtureDensity::Create(noise);
  ASSERT_FALSE(density.ok());
  EXPECT_NE(density.status().message().find("gaussian_probability"), std::string::npos);
  noise = MixtureNoise();
  noise.gaussian_sigma_m = 0.0;
  EXPECT_NE(MixtureDensity::Create(noise).status().message().find("gaussian_sigma_m"), std::string::npos);
  noise = MixtureNoise();
  noise.stable.alpha = 0.8;
  EXPECT_NE(MixtureDensity::Create(noise).status().message().find("alpha"), std::string::npos);
}

}  // namespace
}  // namespace localizer::engine::experiments
