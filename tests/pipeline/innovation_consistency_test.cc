// The reported covariance's inflation (engine/pipeline/innovation_consistency.h): 1 while the
// innovations match the noise model, the NIS-to-pairs ratio of the last frames when they do not.
#include "engine/pipeline/innovation_consistency.h"

#include <gtest/gtest.h>

#include <random>

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

}  // namespace
}  // namespace localizer::engine
