// The associator alone (associator.h): the gate's edge in Mahalanobis distance, global
// nearest neighbour against brute force on random clusters, measurements taken once per
// scan, the cluster statistics, and the bounds on one scan's work (gate search budget,
// greedy matching of clusters too large to solve optimally).
#include "engine/tws/associator.h"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <vector>

#include "engine/tws/chi_square.h"

namespace localizer::engine::tws {
namespace {

template <int D>
Eigen::Matrix<double, D, D> RandomSpd(std::mt19937_64& engine, double scale) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Matrix<double, D, D> b;
  for (int r = 0; r < D; ++r) {
    for (int c = 0; c < D; ++c) b(r, c) = n(engine);
  }
  return scale * (b * b.transpose() + 0.2 * Eigen::Matrix<double, D, D>::Identity());
}

template <int D>
double MahalanobisSquared(const Gaussian<D>& track, const Gaussian<D>& z) {
  const Eigen::Matrix<double, D, 1> nu = z.mean - track.mean;
  return nu.dot((track.covariance + z.covariance).inverse() * nu);
}

// A measurement at Mahalanobis distance^2 = d2 from the track along a random direction.
template <int D>
Gaussian<D> AtDistance(std::mt19937_64& engine, const Gaussian<D>& track, const Eigen::Matrix<double, D, D>& r,
                       double d2) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Matrix<double, D, 1> u;
  for (int k = 0; k < D; ++k) u(k) = n(engine);
  const Eigen::Matrix<double, D, D> s = track.covariance + r;
  const double scale = std::sqrt(d2 / u.dot(s.inverse() * u));
  return {track.mean + scale * u, r};
}

template <int D>
void GateEdgeCase() {
  std::mt19937_64 engine(1600 + D);
  const double g = ChiSquareQuantile(D, 0.9995);
  GnnAssociator<D> associator(g);
  std::vector<int> assigned;
  std::uniform_real_distribution<double> position(-1000.0, 1000.0);
  for (int trial = 0; trial < 200; ++trial) {
    Gaussian<D> track{Eigen::Matrix<double, D, 1>::NullaryExpr([&] { return position(engine); }),
                      RandomSpd<D>(engine, 400.0)};
    const Eigen::Matrix<double, D, D> r = RandomSpd<D>(engine, 100.0);
    for (double factor : {1.0 - 1e-6, 1.0 + 1e-6}) {
      const std::vector<Gaussian<D>> z = {AtDistance<D>(engine, track, r, factor * g)};
      associator.BeginScan(z);
      AssociationStats stats;
      associator.Associate({track}, &assigned, &stats);
      EXPECT_EQ(assigned[0], factor < 1.0 ? 0 : -1) << D << "-D trial " << trial;
      EXPECT_EQ(associator.taken()[0], factor < 1.0 ? 1 : 0);
      EXPECT_EQ(stats.clusters, factor < 1.0 ? 1 : 0);
    }
  }
}

TEST(Associator, GatesOnTheMahalanobisDistanceOfTheInnovation) {
  GateEdgeCase<2>();
  GateEdgeCase<3>();
}

// The minimum over partial one-to-one maps of sum d^2 + g per unmatched track, only pairs
// inside the gate allowed.
template <int D>
double BruteForceCost(const std::vector<Gaussian<D>>& tracks, const std::vector<Gaussian<D>>& z, double g) {
  const int nt = static_cast<int>(tracks.size()), nz = static_cast<int>(z.size());
  std::vector<char> used(nz, 0);
  double best = 1e300;
  std::function<void(int, double)> go = [&](int i, double total) {
    if (i == nt) {
      best = std::min(best, total);
      return;
    }
    go(i + 1, total + g);
    for (int j = 0; j < nz; ++j) {
      const double d2 = MahalanobisSquared(tracks[i], z[j]);
      if (used[j] || d2 > g) continue;
      used[j] = 1;
      go(i + 1, total + d2);
      used[j] = 0;
    }
  };
  go(0, 0.0);
  return best;
}

TEST(Associator, GlobalNearestNeighbourIsOptimalOnRandomCrowdedScenes) {
  // Up to 5 tracks and 6 measurements in a 300 m square, covariances ~(20-40 m)^2: most
  // scenes form multi-track clusters, where per-track nearest neighbour would not be optimal.
  std::mt19937_64 engine(20261216);
  std::uniform_real_distribution<double> position(0.0, 300.0);
  std::uniform_int_distribution<int> count(1, 6);
  const double g = ChiSquareQuantile(2, 0.99);
  GnnAssociator<2> associator(g);
  std::vector<int> assigned;
  int multi_track_clusters = 0;
  for (int trial = 0; trial < 400; ++trial) {
    std::vector<Gaussian<2>> tracks(std::min(count(engine), 5)), z(count(engine));
    for (auto& t : tracks) t = {{position(engine), position(engine)}, RandomSpd<2>(engine, 600.0)};
    for (auto& m : z) m = {{position(engine), position(engine)}, RandomSpd<2>(engine, 300.0)};
    associator.BeginScan(z);
    AssociationStats stats;
    associator.Associate(tracks, &assigned, &stats);
    double total = 0.0;
    std::vector<int> uses(z.size(), 0);
    for (size_t i = 0; i < tracks.size(); ++i) {
      if (assigned[i] < 0) {
        total += g;
        continue;
      }
      const double d2 = MahalanobisSquared(tracks[i], z[assigned[i]]);
      EXPECT_LE(d2, g);  // only pairs inside the gate
      total += d2;
      ++uses[assigned[i]];
      EXPECT_TRUE(associator.taken()[assigned[i]]);
    }
    for (int u : uses) EXPECT_LE(u, 1);  // one track per measurement
    EXPECT_NEAR(total, BruteForceCost(tracks, z, g), 1e-9 * (1.0 + total)) << "trial " << trial;
    if (stats.largest_cluster > 1) ++multi_track_clusters;
  }
  EXPECT_GT(multi_track_clusters, 100);  // the scenes did exercise the assignment solver
}

TEST(Associator, AMeasurementIsTakenOncePerScanAcrossCalls) {
  // Confirmed tracks first, then a tentative one near the same measurement: the second call
  // sees only what the first left.
  GnnAssociator<2> associator(ChiSquareQuantile(2, 0.9995));
  const Eigen::Matrix2d r = 100.0 * Eigen::Matrix2d::Identity();
  const std::vector<Gaussian<2>> z = {{{0.0, 0.0}, r}, {{5000.0, 0.0}, r}};
  const Gaussian<2> near_first{{10.0, 0.0}, r};
  std::vector<int> assigned;
  AssociationStats stats;
  associator.BeginScan(z);
  associator.Associate({near_first}, &assigned, &stats);
  EXPECT_EQ(assigned[0], 0);
  associator.Associate({near_first, {{5005.0, 0.0}, r}}, &assigned, &stats);
  EXPECT_EQ(assigned[0], -1);  // measurement 0 is gone
  EXPECT_EQ(assigned[1], 1);
  EXPECT_EQ(stats.clusters, 2);
  // A new scan frees them again.
  associator.BeginScan(z);
  associator.Associate({near_first}, &assigned, &stats);
  EXPECT_EQ(assigned[0], 0);
}

TEST(Associator, ClustersAreTheGateGraphsComponents) {
  // Three groups 10 km apart: two tracks sharing two measurements, one track with two
  // candidates, one track alone with none.
  GnnAssociator<2> associator(ChiSquareQuantile(2, 0.9995));
  const Eigen::Matrix2d r = 100.0 * Eigen::Matrix2d::Identity();
  const std::vector<Gaussian<2>> z = {{{0.0, 0.0}, r}, {{30.0, 0.0}, r}, {{10000.0, 0.0}, r}, {{10020.0, 5.0}, r}};
  const std::vector<Gaussian<2>> tracks = {{{5.0, 0.0}, r}, {{25.0, 0.0}, r}, {{10015.0, 0.0}, r}, {{20000.0, 0.0}, r}};
  std::vector<int> assigned;
  AssociationStats stats;
  associator.BeginScan(z);
  associator.Associate(tracks, &assigned, &stats);
  EXPECT_EQ(stats.clusters, 2);
  EXPECT_EQ(stats.largest_cluster, 2);
  EXPECT_EQ(assigned[0], 0);  // each the one nearest it: the minimal total
  EXPECT_EQ(assigned[1], 1);
  EXPECT_EQ(assigned[2], 3);  // (10020, 5) is nearer to (10015, 0) than (10000, 0) is
  EXPECT_EQ(assigned[3], -1);
}

TEST(Associator, AThreeDimensionalGateReadsTheThirdAxis) {
  // Same x-y, 10 sigma apart in z: outside; the grid's box test in x-y alone would let it in.
  GnnAssociator<3> associator(ChiSquareQuantile(3, 0.9995));
  const Eigen::Matrix3d r = 100.0 * Eigen::Matrix3d::Identity();
  const Gaussian<3> track{{0.0, 0.0, 0.0}, r};
  std::vector<int> assigned;
  AssociationStats stats;
  const std::vector<Gaussian<3>> above = {{{0.0, 0.0, 10.0 * std::sqrt(200.0)}, r}};
  associator.BeginScan(above);
  associator.Associate({track}, &assigned, &stats);
  EXPECT_EQ(assigned[0], -1);
  const std::vector<Gaussian<3>> level = {{{0.0, 0.0, 1.0 * std::sqrt(200.0)}, r}};
  associator.BeginScan(level);
  associator.Associate({track}, &assigned, &stats);
  EXPECT_EQ(assigned[0], 0);
}

TEST(Associator, AGateSearchSpendsAtMostItsBudget) {
  // Ten measurements inside one track's gate, spread along x; a budget of 4 units (grid rows
  // and measurements looked at) sees at most 3 of them: the track is counted as truncated
  // and takes the best of those it saw, never one it did not.
  const Eigen::Matrix2d r = 100.0 * Eigen::Matrix2d::Identity();
  std::vector<Gaussian<2>> z;
  for (int k = 0; k < 10; ++k) z.push_back({{-9.0 + 2.0 * k, 0.0}, r});
  const Gaussian<2> track{{0.0, 0.0}, r};
  std::vector<int> assigned;
  AssociationStats full_stats, bounded_stats;
  GnnAssociator<2> full(ChiSquareQuantile(2, 0.9995));
  full.BeginScan(z);
  full.Associate({track}, &assigned, &full_stats);
  EXPECT_EQ(full_stats.truncated_gates, 0);
  const int nearest = assigned[0];
  EXPECT_TRUE(nearest == 4 || nearest == 5);  // x = -1 or +1
  GnnAssociator<2> bounded(ChiSquareQuantile(2, 0.9995), AssociatorLimits{4, 65536});
  bounded.BeginScan(z);
  bounded.Associate({track}, &assigned, &bounded_stats);
  EXPECT_EQ(bounded_stats.truncated_gates, 1);
  ASSERT_GE(assigned[0], 0);
  EXPECT_LE(std::count(bounded.taken().begin(), bounded.taken().end(), 1), 1);
}

TEST(Associator, AClusterTooLargeForTheOptimalSolverIsMatchedGreedilyByDistance) {
  // A + R = I, so d2 is the squared distance. Tracks at x = 0 and 3, measurements at x = 1
  // and -1.2: d2 (0,0) = 1, (0,1) = 1.44, (1,0) = 4, (1,1) = 17.64 > g = 15.2 (outside).
  // Optimal: (0,1) + (1,0) = 5.44. Greedy takes the closest pair (0,0) first, which leaves
  // track 1 nothing inside its gate: a miss (1 + g = 16.2). The 2 x 2 cluster has 4 cells:
  // solved optimally with a limit of 4, greedily (and counted) with 3.
  const Eigen::Matrix2d r = 0.5 * Eigen::Matrix2d::Identity();
  const std::vector<Gaussian<2>> tracks = {{{0.0, 0.0}, r}, {{3.0, 0.0}, r}};
  const std::vector<Gaussian<2>> z = {{{1.0, 0.0}, r}, {{-1.2, 0.0}, r}};
  const double g = ChiSquareQuantile(2, 0.9995);
  ASSERT_LT(g, 17.64);
  std::vector<int> assigned;
  AssociationStats optimal_stats, greedy_stats;
  GnnAssociator<2> optimal(g, AssociatorLimits{256, 4});
  optimal.BeginScan(z);
  optimal.Associate(tracks, &assigned, &optimal_stats);
  EXPECT_EQ(optimal_stats.greedy_clusters, 0);
  EXPECT_EQ(assigned[0], 1);
  EXPECT_EQ(assigned[1], 0);
  GnnAssociator<2> greedy(g, AssociatorLimits{256, 3});
  greedy.BeginScan(z);
  greedy.Associate(tracks, &assigned, &greedy_stats);
  EXPECT_EQ(greedy_stats.greedy_clusters, 1);
  EXPECT_EQ(assigned[0], 0);
  EXPECT_EQ(assigned[1], -1);
}

TEST(Associator, CoLocatedTracksAndMeasurementsCostTheBudgetNotTheSquare) {
  // The adversarial scan of the security review: thousands of tracks and plots at one point.
  // Unbounded, this is T x M gate tests and one T x M assignment (cubic); bounded, every
  // gate is truncated, the one cluster is matched greedily, and still each track gets a
  // distinct measurement of those its search saw.
  constexpr int kCount = 4000;
  const Eigen::Matrix2d r = 100.0 * Eigen::Matrix2d::Identity();
  const std::vector<Gaussian<2>> tracks(kCount, Gaussian<2>{{0.0, 0.0}, r});
  const std::vector<Gaussian<2>> z(kCount, Gaussian<2>{{0.0, 0.0}, r});
  GnnAssociator<2> associator(ChiSquareQuantile(2, 0.9995));
  std::vector<int> assigned;
  AssociationStats stats;
  associator.BeginScan(z);
  associator.Associate(tracks, &assigned, &stats);
  EXPECT_EQ(stats.truncated_gates, kCount);
  EXPECT_EQ(stats.greedy_clusters, 1);
  std::vector<int> uses(kCount, 0);
  int matched = 0;
  for (int a : assigned) {
    if (a < 0) continue;
    ++matched;
    ++uses[a];
  }
  for (int u : uses) EXPECT_LE(u, 1);
  EXPECT_GE(matched, 63);  // every search sees ~63 plots; at least that many get one
}

}  // namespace
}  // namespace localizer::engine::tws
