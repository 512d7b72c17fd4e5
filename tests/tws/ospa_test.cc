// OSPA and GOSPA on hand-computed cases, and the identity scoring on a scripted swap.
#include "engine/tws/ospa.h"

#include <gtest/gtest.h>

#include <cmath>

#include "engine/tws/track_scoring.h"

namespace localizer::engine::tws {
namespace {

using V = Eigen::Vector3d;

TEST(Ospa, HandComputedCases) {
  const double c = 10.0, p = 2.0;
  EXPECT_DOUBLE_EQ(Ospa({}, {}, c, p), 0.0);
  EXPECT_DOUBLE_EQ(Ospa({V(0, 0, 0)}, {}, c, p), c);
  EXPECT_DOUBLE_EQ(Ospa({}, {V(0, 0, 0)}, c, p), c);
  EXPECT_NEAR(Ospa({V(0, 0, 0)}, {V(3, 4, 0)}, c, p), 5.0, 1e-12);
  // One pair at 5 m and one false estimate: ((25 + 100) / 2)^(1/2).
  EXPECT_NEAR(Ospa({V(0, 0, 0)}, {V(3, 4, 0), V(100, 0, 0)}, c, p), std::sqrt(62.5), 1e-12);
  // Symmetric, and the optimal pairing is used (not the nearest-first one).
  const std::vector<V> x = {V(0, 0, 0), V(4, 0, 0)}, y = {V(2, 0, 0), V(7, 0, 0)};
  EXPECT_NEAR(Ospa(x, y, c, p), std::sqrt((4.0 + 9.0) / 2.0), 1e-12);
  EXPECT_NEAR(Ospa(y, x, c, p), Ospa(x, y, c, p), 1e-12);
  // Distances are cut at c; order 1.
  EXPECT_NEAR(Ospa({V(0, 0, 0)}, {V(50, 0, 0)}, c, 1.0), c, 1e-12);
}

TEST(Gospa, HandComputedCases) {
  const double c = 10.0, p = 2.0;
  GospaResult r = Gospa({V(0, 0, 0)}, {V(3, 4, 0)}, c, p);
  EXPECT_NEAR(r.gospa, 5.0, 1e-12);
  EXPECT_EQ(r.assigned, 1);
  // One missed truth and one false estimate (too far apart to pair): c^p/2 each.
  r = Gospa({V(0, 0, 0)}, {V(30, 0, 0)}, c, p);
  EXPECT_NEAR(r.gospa, std::sqrt(100.0), 1e-12);
  EXPECT_EQ(r.missed, 1);
  EXPECT_EQ(r.false_tracks, 1);
  r = Gospa({V(0, 0, 0), V(1, 0, 0)}, {}, c, p);
  EXPECT_NEAR(r.gospa, std::sqrt(100.0), 1e-12);
  EXPECT_EQ(r.missed, 2);
  r = Gospa({}, {}, c, p);
  EXPECT_DOUBLE_EQ(r.gospa, 0.0);
}

TEST(TrackScoring, CountsASwapAndPurity) {
  TrackScoring scoring(5.0);
  // Truths 1, 2 followed by tracks 10, 20 for three scans, then the tracks swap.
  for (int k = 0; k < 3; ++k) scoring.Add({{1, V(0, 0, 0)}, {2, V(100, 0, 0)}}, {{10, V(1, 0, 0)}, {20, V(99, 0, 0)}});
  EXPECT_EQ(scoring.identity_switches(), 0);
  scoring.Add({{1, V(0, 0, 0)}, {2, V(100, 0, 0)}}, {{20, V(1, 0, 0)}, {10, V(99, 0, 0)}});
  EXPECT_EQ(scoring.identity_switches(), 2);
  EXPECT_NEAR(scoring.Purity(), 6.0 / 8.0, 1e-12);
  // Two truths 1 m apart with their tracks swapped in distance order but both within the
  // threshold: CLEAR-MOT keeps the previous pairing, no switch.
  TrackScoring close(5.0);
  close.Add({{1, V(0, 0, 0)}, {2, V(1, 0, 0)}}, {{10, V(0, 0, 0)}, {20, V(1, 0, 0)}});
  close.Add({{1, V(0, 0, 0)}, {2, V(1, 0, 0)}}, {{10, V(0.9, 0, 0)}, {20, V(0.1, 0, 0)}});
  EXPECT_EQ(close.identity_switches(), 0);
}

}  // namespace
}  // namespace localizer::engine::tws
