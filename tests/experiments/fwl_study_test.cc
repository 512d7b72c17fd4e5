// The fixed-point word-length study: round-off falls with word length, is negligible
// against the measurement noise at 14-16 bits (the seed's conclusion), and the round-off
// model's computed variance tracks the simulated one.
#include "engine/experiments/fwl_study.h"

#include <gtest/gtest.h>

#include <cmath>

namespace localizer::engine::experiments {
namespace {

FwlResult RunStudy(int system, int runs, uint64_t seed) {
  FwlOptions o;
  o.system = system;
  o.runs = runs;
  o.seed = seed;
  StatusOr<FwlResult> r = RunFwlStudy(o);
  EXPECT_TRUE(r.ok()) << r.status().ToString();
  for (const FwlRow& row : r->rows) {
    std::printf("system %d bits %2d simulated %.3e computed %.3e (unscaled %.3e) overflows %lld\n", system, row.bits,
                row.simulated, row.computed_scaled, row.computed_unscaled, static_cast<long long>(row.overflows));
  }
  return *r;
}

class FwlStudy : public ::testing::TestWithParam<int> {};

TEST_P(FwlStudy, VarianceFallsWithWordLength) {
  const FwlResult r = RunStudy(GetParam(), 500, 1);
  ASSERT_EQ(r.rows.size(), 11u);
  for (size_t i = 2; i < r.rows.size(); ++i) {
    // Two more bits quarter the quantum: the variance falls by 16 in the model; the
    // simulation (500 runs, errors not quite white) falls at every two-bit step.
    EXPECT_LT(r.rows[i].simulated, r.rows[i - 2].simulated / 2.0) << r.rows[i].bits << " bits";
    // The model's 4 per bit, moved by the coefficients' own quantisation at short words.
    EXPECT_NEAR(r.rows[i - 1].computed_scaled / r.rows[i].computed_scaled, 4.0, 1.2);
  }
  // Over the whole table, 6 -> 16 bits: 4^10 ~ 1.05e6 in the model, within a factor of 8.
  const double fall = r.rows.front().simulated / r.rows.back().simulated;
  EXPECT_GT(fall, std::pow(4.0, 10) / 8.0);
  EXPECT_LT(fall, std::pow(4.0, 10) * 8.0);
}

TEST_P(FwlStudy, RoundOffIsNegligibleAt14To16Bits) {
  const FwlResult r = RunStudy(GetParam(), 200, 2);
  const double noise_variance = r.system.measurement_sigma * r.system.measurement_sigma;
  for (const FwlRow& row : r.rows) {
    if (row.bits < 14) continue;
    // Negligible: round-off variance under 1e-3 of the measurement noise variance (std
    // under 3 %; the filtered estimate's own error is ~0.4 sigma_w here).
    EXPECT_LT(row.simulated, 1e-3 * noise_variance) << row.bits << " bits";
    EXPECT_EQ(row.overflows, 0);
  }
  // ...whereas at 6 bits (system 1) / 8 bits (system 2) it is not.
  const FwlRow& short_word = r.rows[GetParam() == 1 ? 0 : 2];
  EXPECT_GT(short_word.simulated, 1e-2 * noise_variance);
}

// The stated factor: within 2 from 12 to 16 bits, where the quantum is far below the
// noise and round-off errors are white; within 5 at every word length (at 6-11 bits the
// errors correlate with the signal through the slow filter poles, and the model - white,
// independent errors - is off by up to ~4: the seed saw the same on its system 2, 75x at
// 10 bits).
TEST_P(FwlStudy, ComputedVarianceTracksSimulated) {
  for (uint64_t seed : {3u, 4u}) {
    const FwlResult r = RunStudy(GetParam(), 500, seed);
    for (const FwlRow& row : r.rows) {
      ASSERT_EQ(row.overflows, 0);
      const double ratio = row.simulated / row.computed_scaled;
      const double factor = row.bits >= 12 ? 2.0 : 5.0;
      EXPECT_GT(ratio, 1.0 / factor) << row.bits << " bits, seed " << seed;
      EXPECT_LT(ratio, factor) << row.bits << " bits, seed " << seed;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Systems, FwlStudy, ::testing::Values(1, 2));

TEST(FwlStudyModel, ScalingMustBeModelledForSystem2) {
  const FwlResult one = RunStudy(1, 20, 4);
  for (const FwlRow& row : one.rows) EXPECT_NEAR(row.computed_unscaled / row.computed_scaled, 1.0, 1e-9);
  // System 2: the simulation agrees with the scaled model and not with the unscaled one
  // (which puts the velocity's round-off in km/s instead of 1/32 km/s, and the position's
  // in km instead of 2 km): they differ by more than 10x from 12 to 16 bits.
  const FwlResult two = RunStudy(2, 500, 4);
  for (const FwlRow& row : two.rows) {
    if (row.bits < 12) continue;
    EXPECT_GT(row.computed_unscaled, 10.0 * row.simulated) << row.bits << " bits";
    EXPECT_LT(row.computed_scaled, 2.0 * row.simulated) << row.bits << " bits";
  }
}

TEST(FwlStudyModel, LyapunovSumOfAScalarSystem) {
  // x' = a x + e: sum_j a^2j q n = q n / (1 - a^2).
  Eigen::Matrix2d phi = Eigen::Matrix2d::Zero();
  phi(0, 0) = 0.9;
  const Eigen::Matrix2d p = RoundOffCovariance(phi, Eigen::Vector2d(2.0, 0.0), 10);
  const double q = std::ldexp(1.0, -20) / 12.0;
  EXPECT_NEAR(p(0, 0), 2.0 * q / (1.0 - 0.81), 1e-12 * q);
}

TEST(FwlStudyModel, RejectsBadOptions) {
  FwlOptions o;
  o.system = 3;
  EXPECT_EQ(RunFwlStudy(o).status().code(), StatusCode::kInvalidArgument);
  o.system = 1;
  o.min_bits = 17;
  EXPECT_EQ(RunFwlStudy(o).status().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace localizer::engine::experiments
