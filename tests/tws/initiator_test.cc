// The initiator alone (initiator.h): one-point and two-point tracks from free measurements,
// their covariance against the spread of the estimates they make, the room limit, and the
// M-of-N confirmation against a brute-force count.
#include "engine/tws/initiator.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <random>
#include <vector>

namespace localizer::engine::tws {
namespace {

using Started2 = Initiator<2>::Started;

Gaussian<2> At(double x, double y, double sigma_m) { return {{x, y}, sigma_m * sigma_m * Eigen::Matrix2d::Identity()}; }

TEST(Initiator, OnePointStartsAtTheMeasurementWithTheVelocityPrior) {
  InitiatorOptions o;
  o.initial_speed_sigma_mps = 150.0;
  Initiator<2> initiator(o);
  Eigen::Matrix2d r;
  r << 400.0, 120.0, 120.0, 900.0;
  const std::vector<Gaussian<2>> z = {{{1000.0, 2000.0}, r}, At(5.0, 6.0, 1.0), At(7.0, 8.0, 1.0)};
  const std::vector<char> taken = {0, 1, 0};
  std::vector<Started2> started;
  initiator.Initiate(z, taken, 1.8, 100, &started);
  ASSERT_EQ(started.size(), 2u);  // the taken one starts nothing
  const Started2& s = started[0];
  EXPECT_EQ(s.x.head<2>(), z[0].mean);
  EXPECT_EQ(s.x.tail<2>(), Eigen::Vector2d::Zero());
  EXPECT_EQ((s.p.topLeftCorner<2, 2>()), r);
  EXPECT_EQ((s.p.topRightCorner<2, 2>()), Eigen::Matrix2d::Zero());
  EXPECT_EQ((s.p.bottomRightCorner<2, 2>()), 150.0 * 150.0 * Eigen::Matrix2d::Identity());
  EXPECT_EQ(s.history.hits, 1);
  EXPECT_EQ(s.history.age, 1);
  EXPECT_EQ(s.history.bits, 1u);
  EXPECT_FALSE(s.history.confirmed);  // M = 3
  EXPECT_EQ(started[1].x.head<2>(), z[2].mean);
}

TEST(Initiator, StartsNoMoreThanTheRoomInIndexOrder) {
  for (Initiation method : {Initiation::kOnePoint, Initiation::kTwoPoint}) {
    InitiatorOptions o;
    o.method = method;
    Initiator<2> initiator(o);
    std::vector<Gaussian<2>> z;
    for (int j = 0; j < 6; ++j) z.push_back(At(1000.0 * j, 0.0, 10.0));
    const std::vector<char> taken(z.size(), 0);
    std::vector<Started2> started;
    initiator.Initiate(z, taken, 0.0, 4, &started);
    if (method == Initiation::kTwoPoint) {  // the first scan only waits
      EXPECT_TRUE(started.empty());
      EXPECT_EQ(initiator.waiting(), 6);
      for (auto& m : z) m.mean.x() += 50.0;
      initiator.Initiate(z, taken, 1.0, 4, &started);
    }
    ASSERT_EQ(started.size(), 4u);
    for (int k = 0; k < 4; ++k) EXPECT_EQ(started[k].x(0), z[k].mean.x());
  }
}

TEST(Initiator, TwoPointPairsWithinReachAndEachPreviousMeasurementOnce) {
  InitiatorOptions o;
  o.method = Initiation::kTwoPoint;
  o.max_speed_mps = 300.0;
  Initiator<2> initiator(o);
  const std::vector<char> none_taken(3, 0);
  std::vector<Started2> started;
  // Scan 0: three measurements wait.
  initiator.Initiate({At(0.0, 0.0, 10.0), At(10000.0, 0.0, 10.0), At(20000.0, 0.0, 10.0)}, none_taken, 0.0, 100,
                     &started);
  EXPECT_TRUE(started.empty());
  // Scan 1, 2 s later: reach = 300 * 2 + 3 sqrt(200 + 200) = 660 m. (500, 0) pairs with
  // (0, 0), 500 m back; (10800, 0) is 800 m from (10000, 0): too far, it waits; (600, 300)
  // is within reach of (0, 0) only, which is used: it waits.
  initiator.Initiate({At(500.0, 0.0, 10.0), At(10800.0, 0.0, 10.0), At(600.0, 300.0, 10.0)}, none_taken, 2.0, 100,
                     &started);
  ASSERT_EQ(started.size(), 1u);
  EXPECT_DOUBLE_EQ(started[0].x(2), 250.0);  // (500 - 0) / 2
  EXPECT_DOUBLE_EQ(started[0].x(3), 0.0);
  EXPECT_EQ(started[0].history.hits, 2);
  EXPECT_EQ(started[0].history.age, 2);
  EXPECT_EQ(started[0].history.bits, 3u);
  EXPECT_EQ(initiator.waiting(), 2);  // 10800 and (600, 300) wait; scan 0's leftovers are gone
  // Scan 2: (600, 300) pairs with a measurement 200 m on; 10800's partner is not there.
  initiator.Initiate({At(800.0, 300.0, 10.0), At(0.0, 0.0, 10.0)}, {0, 0}, 1.0, 100, &started);
  ASSERT_EQ(started.size(), 1u);
  EXPECT_DOUBLE_EQ(started[0].x(2), 200.0);
  EXPECT_EQ(initiator.waiting(), 1);  // (0, 0) waits: scan 0's (0, 0) waited one scan only
}

TEST(Initiator, TwoPointCovarianceIsTheSpreadOfItsEstimates) {
  // A target at p0 with velocity v, measured twice dt apart with noise R1 and R2: the
  // started state's error over many draws has the covariance the initiator states.
  InitiatorOptions o;
  o.method = Initiation::kTwoPoint;
  o.max_speed_mps = 1000.0;
  std::mt19937_64 engine(77);
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Matrix2d r1, r2;
  r1 << 400.0, 150.0, 150.0, 250.0;
  r2 << 900.0, -200.0, -200.0, 300.0;
  const Eigen::Matrix2d l1 = r1.llt().matrixL(), l2 = r2.llt().matrixL();
  const Eigen::Vector2d p0(1000.0, -500.0), v(120.0, 80.0);
  const double dt = 1.8;
  const int draws = 20000;
  Eigen::Matrix4d scatter = Eigen::Matrix4d::Zero();
  Eigen::Matrix4d stated = Eigen::Matrix4d::Zero();
  std::vector<Started2> started;
  for (int k = 0; k < draws; ++k) {
    Initiator<2> initiator(o);
    const Gaussian<2> z1{p0 + l1 * Eigen::Vector2d(n(engine), n(engine)), r1};
    const Gaussian<2> z2{p0 + v * dt + l2 * Eigen::Vector2d(n(engine), n(engine)), r2};
    initiator.Initiate({z1}, {0}, 0.0, 1, &started);
    initiator.Initiate({z2}, {0}, dt, 1, &started);
    ASSERT_EQ(started.size(), 1u);
    Eigen::Vector4d truth;
    truth << p0 + v * dt, v;
    const Eigen::Vector4d e = started[0].x - truth;
    scatter += e * e.transpose();
    stated = started[0].p;  // the same every draw
  }
  scatter /= draws;
  // Sample covariance of 20000 draws: each entry within ~3 sqrt(2 / N) of its scale.
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      const double scale = std::sqrt(stated(r, r) * stated(c, c));
      EXPECT_NEAR(scatter(r, c), stated(r, c), 0.03 * scale) << r << "," << c;
    }
  }
}

TEST(Initiator, ATrackIsConfirmedWhenMOfItsLastNScansHit) {
  // Random hit patterns against a direct count over the last N scans of the history.
  std::mt19937_64 engine(5);
  std::bernoulli_distribution hit(0.6);
  for (int m = 1; m <= 5; ++m) {
    for (int n = m; n <= 7; ++n) {
      InitiatorOptions o;
      o.confirm_hits = m;
      o.confirm_window = n;
      Initiator<2> initiator(o);
      for (int trial = 0; trial < 50; ++trial) {
        TrackHistory h;
        h.bits = 1u;
        h.age = h.hits = 1;
        std::vector<bool> pattern = {true};
        bool expected = m <= 1;
        h.confirmed = expected;
        EXPECT_EQ(initiator.Confirm(h), expected);
        for (int scan = 1; scan < 12; ++scan) {
          const bool b = hit(engine);
          pattern.push_back(b);
          h.Record(b);
          int in_window = 0;
          for (int k = 0; k < n && k < static_cast<int>(pattern.size()); ++k)
            in_window += pattern[pattern.size() - 1 - k];
          expected = expected || in_window >= m;  // never withdrawn
          EXPECT_EQ(initiator.Confirm(h), expected) << m << " of " << n << ", scan " << scan;
          EXPECT_EQ(h.confirmed, expected);
        }
      }
    }
  }
}

TEST(Initiator, AStartedTrackIsConfirmedAtOnceWhenItsHitsReachM) {
  InitiatorOptions o;
  o.method = Initiation::kTwoPoint;
  o.confirm_hits = 2;
  Initiator<2> two_point(o);
  std::vector<Started2> started;
  two_point.Initiate({At(0.0, 0.0, 10.0)}, {0}, 0.0, 10, &started);
  two_point.Initiate({At(100.0, 0.0, 10.0)}, {0}, 1.0, 10, &started);
  ASSERT_EQ(started.size(), 1u);
  EXPECT_TRUE(started[0].history.confirmed);
  o.method = Initiation::kOnePoint;
  Initiator<2> one_point(o);
  one_point.Initiate({At(0.0, 0.0, 10.0)}, {0}, 0.0, 10, &started);
  EXPECT_FALSE(started[0].history.confirmed);  // one hit of two
  o.confirm_hits = 1;
  Initiator<2> m1(o);
  m1.Initiate({At(0.0, 0.0, 10.0)}, {0}, 0.0, 10, &started);
  EXPECT_TRUE(started[0].history.confirmed);
}

TEST(Initiator, ThreeDimensionalOnePointUsesTheFullCovariance) {
  Initiator<3> initiator(InitiatorOptions{});
  Eigen::Matrix3d r;
  r << 100.0, 10.0, 5.0, 10.0, 200.0, 20.0, 5.0, 20.0, 50.0;
  std::vector<Initiator<3>::Started> started;
  initiator.Initiate({{{1.0, 2.0, 3.0}, r}}, {0}, 0.0, 1, &started);
  ASSERT_EQ(started.size(), 1u);
  EXPECT_EQ((started[0].p.topLeftCorner<3, 3>()), r);
  EXPECT_EQ(started[0].x.head<3>(), Eigen::Vector3d(1.0, 2.0, 3.0));
}

}  // namespace
}  // namespace localizer::engine::tws
