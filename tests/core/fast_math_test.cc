// The accuracy the header of engine/core/fast_math.h states, checked against libm in double.
#include "engine/core/fast_math.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

namespace localizer::engine {
namespace {

TEST(FastMath, ExpRelativeErrorBelowThreeTenMillionths) {
  double worst = 0.0;
  // x = -87, -86.999, ..., 87.999: the points the former accumulating loop (x <= 88) reached.
  for (int i = -87000; i < 88000; ++i) {
    const double x = i / 1000.0;
    const double exact = std::exp(static_cast<double>(static_cast<float>(x)));
    const double got = FastExp(static_cast<float>(x));
    worst = std::max(worst, std::abs(got - exact) / exact);
  }
  EXPECT_LT(worst, 3e-7);
  EXPECT_EQ(FastExp(-1000.0f), FastExp(-87.0f));  // clamped, no denormals or zero-division
  EXPECT_GT(FastExp(-1000.0f), 0.0f);
}

TEST(FastMath, LogErrorBelowThreeTenMillionthsScaledByTheResult) {
  double worst = 0.0;
  for (int i = 0; 1e-30 * std::pow(1.0007, i) < 1e30; ++i) {  // x = 1e-30 * 1.0007^i below 1e30
    const float xf = static_cast<float>(1e-30 * std::pow(1.0007, i));
    const double exact = std::log(static_cast<double>(xf));
    worst = std::max(worst, std::abs(FastLog(xf) - exact) / std::max(1.0, std::abs(exact)));
  }
  EXPECT_LT(worst, 3e-7);
}

TEST(FastMath, NormalQuantileMatchesTheInverseErf) {
  // Reference: invert the standard normal CDF by bisection in double.
  const auto quantile = [](double u) {
    double lo = -9.0, hi = 9.0;
    for (int i = 0; i < 80; ++i) {
      const double mid = 0.5 * (lo + hi);
      (0.5 * std::erfc(-mid / std::sqrt(2.0)) < u ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
  };
  double worst_centre = 0.0, worst_tail = 0.0;
  // u from 1e-7 below 1 in steps of 1e-6 in the tails (u < 0.01, u > 0.99) and 1e-4 between,
  // counted in units of 1e-7: k = 1, 11, ..., 99991, 100001, 101001, ...
  for (int k = 1; k < 10000000; k += (k < 100000 || k > 9900000) ? 10 : 1000) {
    const double u = k / 1e7;
    const float uf = static_cast<float>(u);
    const double error = std::abs(NormalFromUniform(uf) - quantile(static_cast<double>(uf)));
    double& worst = (u >= 1e-3 && u <= 1.0 - 1e-3) ? worst_centre : worst_tail;
    worst = std::max(worst, error);
  }
  EXPECT_LT(worst_centre, 2e-5);
  EXPECT_LT(worst_tail, 2e-3);
  // The extreme draws UniformFromCounter can produce, (0.5) / 2^23 and (2^23 - 0.5) / 2^23,
  // stay finite and symmetric: about +-5.3 sigma.
  const float lowest = 0.5f / 8388608.0f, highest = (8388608.0f - 0.5f) / 8388608.0f;
  ASSERT_LT(highest, 1.0f);
  EXPECT_NEAR(NormalFromUniform(lowest), quantile(static_cast<double>(lowest)), 0.02);
  EXPECT_NEAR(NormalFromUniform(lowest), -NormalFromUniform(highest), 0.02);
  EXPECT_NEAR(NormalFromUniform(highest), quantile(static_cast<double>(highest)), 0.02);
  EXPECT_NEAR(NormalFromUniform(highest), 5.3, 0.1);
}

// Counter-based draws: uniform (chi-square over 64 bins), uncorrelated between neighbours,
// and different keys give different streams.
TEST(FastMath, CounterUniformsAreUniformAndIndependent) {
  const int n = 1 << 20, bins = 64;
  std::vector<int> counts(bins, 0);
  double lag_product = 0.0, previous = 0.0;
  for (int i = 0; i < n; ++i) {
    const float u = UniformFromCounter(12345u, static_cast<uint32_t>(i));
    ASSERT_GT(u, 0.0f);
    ASSERT_LT(u, 1.0f);
    ++counts[static_cast<int>(u * bins)];
    lag_product += (u - 0.5) * (previous - 0.5);
    previous = u;
  }
  double chi2 = 0.0;
  const double expected = static_cast<double>(n) / bins;
  for (int c : counts) chi2 += (c - expected) * (c - expected) / expected;
  EXPECT_LT(chi2, 120.0);  // 63 degrees of freedom: P(chi2 > 120) < 1e-5
  // Lag-1 correlation of uniforms: std 1/sqrt(n) ~ 0.001 in units of the variance 1/12.
  EXPECT_LT(std::abs(lag_product / n * 12.0), 0.005);
  int same = 0;
  for (uint32_t i = 0; i < 1000; ++i) same += UniformFromCounter(1u, i) == UniformFromCounter(2u, i);
  EXPECT_LT(same, 5);
}

}  // namespace
}  // namespace localizer::engine

namespace localizer::engine {
namespace {

TEST(FastMath, BoxMullerPairMatchesDoublePrecision) {
  double worst = 0.0;
  for (int i = 0; i < 73; ++i) {  // u1 = 1e-4, 0.0138, ..., 0.9865
    const float u1 = 1e-4f + 0.0137f * static_cast<float>(i);
    for (int j = 0; j < 910; ++j) {  // u2 = 0, 0.0011, ..., 0.9999
      const float u2 = 0.0011f * static_cast<float>(j);
      float z1, z2;
      NormalPairFromUniforms(u1, u2, &z1, &z2);
      const double r = std::sqrt(-2.0 * std::log(static_cast<double>(u1)));
      const double theta = 2.0 * std::numbers::pi * static_cast<double>(u2);
      worst = std::max({worst, std::abs(z1 - r * std::cos(theta)), std::abs(z2 - r * std::sin(theta))});
    }
  }
  EXPECT_LT(worst, 5e-6);  // float: a few ulp of r ~ 4
}

TEST(FastMath, BoxMullerDrawsHaveUnitVarianceAndNoCorrelation) {
  const int n = 1 << 18;
  double s1 = 0, s2 = 0, s11 = 0, s22 = 0, s12 = 0, kurt = 0;
  for (int i = 0; i < n; ++i) {
    float z1, z2;
    NormalPairFromUniforms(UniformFromCounter(7u, 2u * i), UniformFromCounter(7u, 2u * i + 1), &z1, &z2);
    s1 += z1, s2 += z2, s11 += z1 * z1, s22 += z2 * z2, s12 += z1 * z2;
    kurt += static_cast<double>(z1) * z1 * z1 * z1;
  }
  // Standard errors at n = 262144: mean 0.002, variance 0.003, correlation 0.002, E[z^4] 0.02.
  EXPECT_NEAR(s1 / n, 0.0, 0.01);
  EXPECT_NEAR(s2 / n, 0.0, 0.01);
  EXPECT_NEAR(s11 / n, 1.0, 0.015);
  EXPECT_NEAR(s22 / n, 1.0, 0.015);
  EXPECT_NEAR(s12 / n, 0.0, 0.01);
  EXPECT_NEAR(kurt / n, 3.0, 0.1);
}

}  // namespace
}  // namespace localizer::engine
