#include "clients/io/score.h"

#include <gtest/gtest.h>

#include <cmath>

namespace localizer::io {
namespace {

// A source moving at 1 m/s along x, truth every 0.1 s over [0, 10] s.
std::vector<engine::TruthRow> LineTruth() {
  std::vector<engine::TruthRow> truth;
  for (int i = 0; i <= 100; ++i) {
    engine::TruthRow row;
    row.t_s = 0.1 * i;
    row.position_m = engine::Vec3(row.t_s, 5.0, -3.0);
    row.velocity_mps = engine::Vec3(1.0, 0.0, 0.0);
    truth.push_back(row);
  }
  return truth;
}

EstimateRow At(double t_s, const engine::Vec3& offset_m, bool initialised = true) {
  EstimateRow row;
  row.t_s = t_s;
  row.position_m = engine::Vec3(t_s, 5.0, -3.0) + offset_m;
  row.initialised = initialised;
  return row;
}

TEST(Score, ConstantOffsetGivesThatError) {
  std::vector<EstimateRow> estimates;
  // Times between truth rows exercise the interpolation.
  for (int i = 0; i < 40; ++i) estimates.push_back(At(0.137 + 0.25 * i, {0.0, 0.3, 0.0}));
  auto score = Score(LineTruth(), estimates);
  ASSERT_TRUE(score.ok()) << score.status().ToString();
  EXPECT_EQ(score->count, 40);
  EXPECT_NEAR(score->rmse_m, 0.3, 1e-9);
  EXPECT_NEAR(score->median_m, 0.3, 1e-9);
  EXPECT_NEAR(score->p95_m, 0.3, 1e-9);
  EXPECT_NEAR(score->max_m, 0.3, 1e-9);
}

TEST(Score, StatisticsFollowTheDocumentedDefinitions) {
  // Errors 1..20 m: rmse = sqrt(mean k^2), median = 10.5, p95 = e_(19) = 19, max = 20.
  std::vector<EstimateRow> estimates;
  for (int k = 1; k <= 20; ++k) estimates.push_back(At(0.4 * k, {0.0, 0.0, double(k)}));
  auto score = Score(LineTruth(), estimates);
  ASSERT_TRUE(score.ok());
  double sum_sq = 0;
  for (int k = 1; k <= 20; ++k) sum_sq += k * k;
  EXPECT_NEAR(score->rmse_m, std::sqrt(sum_sq / 20), 1e-9);
  EXPECT_NEAR(score->median_m, 10.5, 1e-9);
  EXPECT_NEAR(score->p95_m, 19.0, 1e-9);
  EXPECT_NEAR(score->max_m, 20.0, 1e-9);
}

TEST(Score, SkipsUninitialisedAndOutOfSpan) {
  std::vector<EstimateRow> estimates = {At(1.0, {0.1, 0, 0}), At(2.0, {50, 0, 0}, false), At(-0.5, {50, 0, 0}),
                                        At(10.5, {50, 0, 0})};
  auto score = Score(LineTruth(), estimates);
  ASSERT_TRUE(score.ok());
  EXPECT_EQ(score->count, 1);
  EXPECT_NEAR(score->max_m, 0.1, 1e-9);
}

TEST(Score, NothingScorableIsAnError) {
  auto score = Score(LineTruth(), {At(2.0, {0, 0, 0}, false)});
  ASSERT_FALSE(score.ok());
  EXPECT_EQ(score.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_FALSE(Score({}, {At(2.0, {0, 0, 0})}).ok());
}

TEST(Score, NonFiniteEstimateScoresAsInfinite) {
  auto score = Score(LineTruth(), {At(1.0, {NAN, 0, 0}), At(2.0, {0.2, 0, 0})});
  ASSERT_TRUE(score.ok());
  EXPECT_TRUE(std::isinf(score->rmse_m));
}

TEST(Score, FormatIsOneKeyValueLine) {
  ScoreResult score{31, 0.25, 0.2, 0.5, 0.75};
  EXPECT_EQ(FormatScore(score), "n=31, rmse_m=0.25, median_m=0.2, p95_m=0.5, max_m=0.75");
}

}  // namespace
}  // namespace localizer::io
