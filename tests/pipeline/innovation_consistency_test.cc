// The reported covariance's inflation (engine/pipeline/innovation_consistency.h): 1 while the
// innovations match the noise model, the NIS-to-pairs ratio of the last frames when they do
// not, and the state's share when that ratio hides a lagging, overconfident track.
#include "engine/pipeline/innovation_consistency.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

namespace localizer::engine {
namespace {

TEST(InnovationConsistency, ConsistentInnovationsLeaveTheCovarianceAlone) {
  InnovationConsistency c;
  EXPECT_EQ(c.Inflation(), 1.0);
  std::mt19937_64 rng(3);
  std::chi_squared_distribution<double> chi2(3.0);  // 3 pairs, consistent
  double sum = 0.0;
  constexpr int kFrames = 4000;
  for (int i = 0; i < kFrames; ++i) {
    c.Add(chi2(rng), 3);
    sum += c.Inflation();
  }
  // The mean of 4 frames' chi-square(3) / 3 exceeds 1 about half the time, by ~0.4 typically.
  EXPECT_LT(sum / kFrames, 1.25);
}

TEST(InnovationConsistency, InnovationsTenTimesTheModelInflateTenfoldAndOldFramesLeave) {
  InnovationConsistency c;
  for (int i = 0; i < InnovationConsistency::kFrames; ++i) c.Add(30.0, 3);
  EXPECT_DOUBLE_EQ(c.Inflation(), 10.0);
  for (int i = 0; i < InnovationConsistency::kFrames; ++i) c.Add(3.0, 3);
  EXPECT_DOUBLE_EQ(c.Inflation(), 1.0);  // the bad frames left the window
  c.Add(24.0, 4);                        // one bad frame of four: (24 + 3 x 3) / (4 + 3 x 3)
  EXPECT_DOUBLE_EQ(c.Inflation(), 33.0 / 13.0);
  c.Reset();
  EXPECT_EQ(c.Inflation(), 1.0);
  c.Add(-1.0, 3);  // refused: not a NIS
  c.Add(5.0, 0);   // refused: no pairs
  EXPECT_EQ(c.Inflation(), 1.0);
}

// A converged track (its predicted TDOA spread a tenth of the noise's sd) that lags: every
// pair's innovation is 2 noise sds. The NIS ratio says 4 (sd x 2); the state must be
// inflated until its own spread explains the innovations: 4 / (1 + 0.01 k) = 1, k = 300.
TEST(InnovationConsistency, ALaggingConvergedTrackIsInflatedByTheStatesShare) {
  InnovationConsistency c;
  const std::vector<UpdateReport::NisTerm> terms(3, {4.0, 1.0, 0.01});
  for (int i = 0; i < InnovationConsistency::kFrames; ++i) c.Add(3 * 4.0 / 1.01, 3, terms);
  EXPECT_NEAR(c.Inflation(), 300.0, 3.0);
  // Without the terms (a Kalman filter's report) the ratio alone.
  InnovationConsistency ratio_only;
  for (int i = 0; i < InnovationConsistency::kFrames; ++i) ratio_only.Add(3 * 4.0 / 1.01, 3);
  EXPECT_NEAR(ratio_only.Inflation(), 4.0 / 1.01, 1e-9);
}

// Innovations drawn from the model (state spread a tenth of the noise's sd, as above): the
// significance gate keeps the state's share out nearly always.
TEST(InnovationConsistency, ConsistentInnovationsWithTermsRarelyInflate) {
  InnovationConsistency c;
  std::mt19937_64 rng(4);
  std::normal_distribution<double> e(0.0, std::sqrt(1.01));
  constexpr int kFrames = 4000;
  int inflated_tenfold = 0;
  double sum = 0.0;
  for (int i = 0; i < kFrames; ++i) {
    std::vector<UpdateReport::NisTerm> terms;
    double nis = 0.0;
    for (int p = 0; p < 3; ++p) {
      const double x = e(rng);
      terms.push_back({x * x, 1.0, 0.01});
      nis += x * x / 1.01;
    }
    c.Add(nis, 3, terms);
    const double k = c.Inflation();
    sum += k;
    inflated_tenfold += k > 10.0;
  }
  std::printf("mean inflation %.3f, windows above 10x %d of %d\n", sum / kFrames, inflated_tenfold, kFrames);
  EXPECT_LT(inflated_tenfold, kFrames / 50);  // the gate's 1 %, with overlapping windows
}

}  // namespace
}  // namespace localizer::engine
