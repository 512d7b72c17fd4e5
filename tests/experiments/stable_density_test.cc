#include "engine/experiments/stable_density.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "tests/sim/npy_reader.h"

namespace localizer::engine::experiments {
namespace {

// Nolan's reference tables as shipped by Debian's python3-scipy (deploy/install.sh installs
// it), both in S1 ("Z1"), columns x, value, alpha, beta, pct, stored fortran_order True
// (tests/sim/alpha_stable_test.cc describes them): the pdf table holds f(x), the cdf table
// F(x), at the x of the nominal percentiles pct of S1(alpha, beta, 1, 0).
constexpr char kTableDir[] = "/usr/lib/python3/dist-packages/scipy/stats/tests/data/levy_stable/";

const testing::NpyMatrix* LoadTable(const std::string& name) {
  StatusOr<testing::NpyMatrix> read = testing::ReadNpyMatrix(std::string(kTableDir) + name);
  return read.ok() && read->cols == 5 ? new testing::NpyMatrix(std::move(*read)) : nullptr;
}

const testing::NpyMatrix* PdfTable() {
  static const testing::NpyMatrix* table = LoadTable("stable-Z1-pdf-sample-data.npy");
  return table;
}

const testing::NpyMatrix* CdfTable() {
  static const testing::NpyMatrix* table = LoadTable("stable-Z1-cdf-sample-data.npy");
  return table;
}

TEST(StableDensity, MatchesNolansPdfTableForEveryAlphaAboveOne) {
  const testing::NpyMatrix* t = PdfTable();
  ASSERT_NE(t, nullptr) << "cannot read the pdf table (install python3-scipy: deploy/install.sh)";
  int checked = 0;
  for (int64_t r = 0; r < t->rows; ++r) {
    const double x = t->at(r, 0), f = t->at(r, 1), alpha = t->at(r, 2), beta = t->at(r, 3);
    if (!(alpha > 1.05 && alpha < 1.95)) continue;  // 1.1 .. 1.9: the supported range
    // Relative 1e-6: the quadrature is good to 1e-9; the table's own digits set the rest.
    EXPECT_NEAR(StableStandardDensity(x, alpha, beta), f, 1e-6 * f)
        << "alpha " << alpha << " beta " << beta << " x " << x;
    ++checked;
  }
  // alpha 1.1..1.9 x beta -1..1 step 0.1 x 11 percentiles, less one row the file lacks.
  EXPECT_EQ(checked, 9 * 21 * 11 - 1);
}

TEST(StableDensity, IsContinuousThroughZero) {
  // f(0) has its own formula; the integral form must meet it on both sides.
  for (const double beta : {-1.0, 0.0, 0.5, 1.0}) {
    const double at_zero = StableStandardDensity(0.0, 1.7, beta);
    EXPECT_NEAR(StableStandardDensity(1e-5, 1.7, beta), at_zero, 1e-5 * at_zero) << beta;
    EXPECT_NEAR(StableStandardDensity(-1e-5, 1.7, beta), at_zero, 1e-5 * at_zero) << beta;
  }
}

TEST(StableDensityTable, InterpolatesTheDirectDensityOffTheGrid) {
  StatusOr<StableDensityTable> table = StableDensityTable::Create({1.7, 1.0, 10.0, -3.0});
  ASSERT_TRUE(table.ok()) << table.status().ToString();
  // x in metres of S1(1.7, 1, 10, -3); u = (x + 3) / 10 is off the 0.02 grid.
  for (const double u : {-7.013, -3.3333, -1.011, -0.331, 0.0071, 0.777, 4.321, 33.3, 59.99}) {
    const double expected = std::log(StableStandardDensity(u, 1.7, 1.0) / 10.0);
    EXPECT_NEAR(table->LogDensity(10.0 * u - 3.0), expected, 1e-4) << u;
  }
  // Beyond the table: the power tail meets the table and follows x^-(1 + alpha).
  for (const double u : {80.0, 300.0, 2000.0}) {
    const double expected = std::log(StableStandardDensity(u, 1.7, 1.0) / 10.0);
    EXPECT_NEAR(table->LogDensity(10.0 * u - 3.0), expected, 0.01) << u;
  }
  // The short left tail of beta = 1 only decays; it stays finite (floored).
  EXPECT_TRUE(std::isfinite(table->LogDensity(-1e6)));
  EXPECT_LT(table->LogDensity(-1e6), -600.0);
}

// Trapezoid rule of exp(LogDensity) over [lo, hi], with the step nearest h that divides it.
double Mass(const StableDensityTable& table, double lo, double hi, double h) {
  const int n = std::max(1, static_cast<int>(std::lround((hi - lo) / h)));
  const double step = (hi - lo) / n;
  double sum = 0.5 * (std::exp(table.LogDensity(lo)) + std::exp(table.LogDensity(hi)));
  for (int i = 1; i < n; ++i) sum += std::exp(table.LogDensity(lo + i * step));
  return sum * step;
}

// Mass of S1(1.7, beta, 1, 0) beyond |x| = x_far on one side, from the tail asymptote
// P(X > x) ~ (1 + beta) C x^-alpha, C = Gamma(alpha) sin(pi alpha / 2) / pi (left: 1 - beta).
double TailMass(double beta_sign_weight, double x_far) {
  const double c = std::tgamma(1.7) * std::sin(0.85 * std::numbers::pi) / std::numbers::pi;
  return beta_sign_weight * c * std::pow(x_far, -1.7);
}

TEST(StableDensityTable, IntegratesToOne) {
  for (const double beta : {0.0, 1.0}) {
    StatusOr<StableDensityTable> table = StableDensityTable::Create({1.7, beta, 1.0, 0.0});
    ASSERT_TRUE(table.ok());
    const double x_far = 2000.0;
    const double mass = Mass(*table, -x_far, x_far, 0.005) + TailMass(1.0 + beta, x_far) + TailMass(1.0 - beta, x_far);
    EXPECT_NEAR(mass, 1.0, 1e-4) << beta;
  }
}

TEST(StableDensityTable, CumulatesToNolansCdfTable) {
  const testing::NpyMatrix* t = CdfTable();
  ASSERT_NE(t, nullptr) << "cannot read the cdf table (install python3-scipy: deploy/install.sh)";
  int checked = 0;
  for (const double beta : {0.0, 1.0}) {
    StatusOr<StableDensityTable> table = StableDensityTable::Create({1.7, beta, 1.0, 0.0});
    ASSERT_TRUE(table.ok());
    for (int64_t r = 0; r < t->rows; ++r) {
      if (std::abs(t->at(r, 2) - 1.7) > 1e-9 || std::abs(t->at(r, 3) - beta) > 1e-9) continue;
      // F(x) = mass below -60 (the tail asymptote) + the table's mass from -60 to x.
      const double x = t->at(r, 0);
      const double below = TailMass(1.0 - beta, 60.0) + Mass(*table, -60.0, x, 0.001);
      EXPECT_NEAR(below, t->at(r, 1), 1e-4) << "beta " << beta << " x " << x;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 22);
}

TEST(StableDensityTable, AlphaTwoIsTheGaussianOfVarianceTwoScaleSquared) {
  StatusOr<StableDensityTable> table = StableDensityTable::Create({2.0, 0.0, 3.0, 1.0});
  ASSERT_TRUE(table.ok());
  const double variance = 2.0 * 9.0;
  for (const double x : {-5.0, 1.0, 4.0}) {
    const double expected = -0.5 * (x - 1.0) * (x - 1.0) / variance - 0.5 * std::log(2.0 * std::numbers::pi * variance);
    EXPECT_NEAR(table->LogDensity(x), expected, 1e-12);
  }
}

TEST(StableDensityTable, RejectsUnsupportedParametersNamingTheField) {
  StatusOr<StableDensityTable> table = StableDensityTable::Create({1.0, 0.0, 1.0, 0.0});
  ASSERT_FALSE(table.ok());
  EXPECT_NE(table.status().message().find("alpha"), std::string::npos);
  table = StableDensityTable::Create({1.5, 1.5, 1.0, 0.0});
  ASSERT_FALSE(table.ok());
  EXPECT_NE(table.status().message().find("beta"), std::string::npos);
}

}  // namespace
}  // namespace localizer::engine::experiments
