// The updater alone (updater.h): prediction against the dense F P F^T + Q and the closed
// form of a coasting track's growth, the update against the dense Kalman equations, the
// filter's consistency (NEES) on simulated constant-velocity targets, and the steady-state
// form freezing at the Riccati limit and unfreezing on a miss or a new scan interval.
#include "engine/tws/updater.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <cmath>
#include <cstdio>
#include <random>

#include "engine/tws/steady_state_gain.h"

namespace localizer::engine::tws {
namespace {

using K2 = Cv<2>;

Eigen::Matrix4d Transition(double dt) {
  Eigen::Matrix4d f = Eigen::Matrix4d::Identity();
  f.topRightCorner<2, 2>() = dt * Eigen::Matrix2d::Identity();
  return f;
}

Eigen::Matrix4d ProcessNoise(double dt, double q) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Zero();
  const Eigen::Matrix2d i = Eigen::Matrix2d::Identity();
  m.topLeftCorner<2, 2>() = q * std::pow(dt, 4) / 4.0 * i;
  m.topRightCorner<2, 2>() = q * std::pow(dt, 3) / 2.0 * i;
  m.bottomLeftCorner<2, 2>() = q * std::pow(dt, 3) / 2.0 * i;
  m.bottomRightCorner<2, 2>() = q * dt * dt * i;
  return m;
}

Eigen::Matrix4d RandomCov(std::mt19937_64& engine) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Matrix4d b;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) b(r, c) = n(engine) * (r < 2 ? 30.0 : 5.0);
  }
  return b * b.transpose() + Eigen::Matrix4d::Identity();
}

TEST(Updater, PredictIsTheDenseTimeUpdate) {
  std::mt19937_64 engine(11);
  std::normal_distribution<double> n(0.0, 100.0);
  const UpdaterOptions o{3.0, FilterForm::kKalman, 1e-3};
  const KalmanUpdater<2> updater(o);
  for (int trial = 0; trial < 100; ++trial) {
    const K2::State x(n(engine), n(engine), n(engine), n(engine));
    const Eigen::Matrix4d p = RandomCov(engine);
    const double dt = 0.1 + trial * 0.05;
    FilterState<2> f = KalmanUpdater<2>::Start(x, p);
    updater.Predict(f, dt);
    const Eigen::Matrix4d fm = Transition(dt);
    EXPECT_LT((f.x - fm * x).cwiseAbs().maxCoeff(), 1e-9 * (1.0 + x.cwiseAbs().maxCoeff()));
    const Eigen::Matrix4d want = fm * p * fm.transpose() + ProcessNoise(dt, 9.0);
    EXPECT_LT((f.p - want).cwiseAbs().maxCoeff(), 1e-9 * want.cwiseAbs().maxCoeff());
  }
  // dt <= 0: nothing happens.
  FilterState<2> f = KalmanUpdater<2>::Start(K2::State(1, 2, 3, 4), Eigen::Matrix4d::Identity());
  updater.Predict(f, 0.0);
  updater.Predict(f, -1.0);
  EXPECT_EQ(f.x, K2::State(1, 2, 3, 4));
  EXPECT_EQ(f.p, Eigen::Matrix4d::Identity());
}

TEST(Updater, ACoastingTracksPositionVarianceGrowsAsTheClosedForm) {
  // n predictions of T from P0 = diag(sp^2, sv^2) per axis, white acceleration q:
  //   A_n = sp^2 + (n T)^2 sv^2 + q T^4 n (4 n^2 - 1) / 12
  // (the noise of step i reaches the position with weight T^2 (n - i - 1/2)).
  const double sp = 30.0, sv = 20.0, sigma_a = 4.0, t = 60.0 / 33.0;
  const KalmanUpdater<2> updater({sigma_a, FilterForm::kKalman, 1e-3});
  Eigen::Matrix4d p0 = Eigen::Matrix4d::Zero();
  p0.diagonal() << sp * sp, sp * sp, sv * sv, sv * sv;
  FilterState<2> f = KalmanUpdater<2>::Start(K2::State::Zero(), p0);
  for (int n = 1; n <= 40; ++n) {
    updater.Predict(f, t);
    KalmanUpdater<2>::Miss(f);
    const double want =
        sp * sp + n * n * t * t * sv * sv + sigma_a * sigma_a * std::pow(t, 4) * n * (4.0 * n * n - 1) / 12.0;
    EXPECT_NEAR(KalmanUpdater<2>::LargestPositionVariance(f), want, 1e-9 * want) << n;
  }
}

TEST(Updater, UpdateIsTheDenseKalmanUpdate) {
  std::mt19937_64 engine(12);
  std::normal_distribution<double> n(0.0, 100.0);
  const KalmanUpdater<2> updater({5.0, FilterForm::kKalman, 1e-3});
  Eigen::Matrix<double, 2, 4> h = Eigen::Matrix<double, 2, 4>::Zero();
  h.leftCols<2>().setIdentity();
  for (int trial = 0; trial < 100; ++trial) {
    const K2::State x(n(engine), n(engine), n(engine), n(engine));
    const Eigen::Matrix4d p = RandomCov(engine);
    Eigen::Matrix2d r;
    r << 400.0, 100.0 * (trial % 3 - 1), 100.0 * (trial % 3 - 1), 900.0;
    const Gaussian<2> z{{n(engine), n(engine)}, r};
    FilterState<2> f = KalmanUpdater<2>::Start(x, p);
    const Gaussian<2> expected = KalmanUpdater<2>::Expected(f);
    EXPECT_EQ(expected.mean, h * x);
    EXPECT_LT((expected.covariance - h * p * h.transpose()).cwiseAbs().maxCoeff(), 1e-12);
    updater.Update(f, z, 1.0);
    const Eigen::Matrix2d s = h * p * h.transpose() + r;
    const Eigen::Matrix<double, 4, 2> gain = p * h.transpose() * s.inverse();
    const K2::State x_want = x + gain * (z.mean - h * x);
    const Eigen::Matrix4d p_want = (Eigen::Matrix4d::Identity() - gain * h) * p;
    EXPECT_LT((f.x - x_want).cwiseAbs().maxCoeff(), 1e-9 * (1.0 + x_want.cwiseAbs().maxCoeff()));
    EXPECT_LT((f.p - p_want).cwiseAbs().maxCoeff(), 1e-9 * p.cwiseAbs().maxCoeff());
    EXPECT_EQ(f.p, f.p.transpose());                                                           // symmetrised
    EXPECT_LT((f.last_gain - gain).cwiseAbs().maxCoeff(), 1e-9 * gain.cwiseAbs().maxCoeff());  // kept
    EXPECT_TRUE(f.have_last_gain);
    // Physics: a measurement never increases the uncertainty.
    EXPECT_GE((p - f.p).eigenvalues().real().minCoeff(), -1e-9 * p.norm());
  }
}

// Normalised estimation error squared of a filter over a simulated constant-velocity target
// with the noise the filter assumes; its mean is the state dimension (4) for a consistent
// filter.
double MeanNees(FilterForm form, uint64_t seed) {
  std::mt19937_64 engine(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  const double sigma_a = 2.0, sigma_r = 30.0, t = 1.0;
  const KalmanUpdater<2> updater({sigma_a, form, 1e-3});
  const Eigen::Matrix2d r = sigma_r * sigma_r * Eigen::Matrix2d::Identity();
  double sum = 0.0;
  int count = 0;
  for (int run = 0; run < 200; ++run) {
    K2::State truth(0.0, 0.0, 100.0, -50.0);
    const Gaussian<2> first{truth.head<2>() + sigma_r * Eigen::Vector2d(n(engine), n(engine)), r};
    Eigen::Matrix4d p0 = Eigen::Matrix4d::Zero();
    p0.topLeftCorner<2, 2>() = r;
    p0.bottomRightCorner<2, 2>() = 200.0 * 200.0 * Eigen::Matrix2d::Identity();
    K2::State x0 = K2::State::Zero();
    x0.head<2>() = first.mean;
    FilterState<2> f = KalmanUpdater<2>::Start(x0, p0);
    for (int k = 1; k <= 60; ++k) {
      const Eigen::Vector2d a = sigma_a * Eigen::Vector2d(n(engine), n(engine));
      truth.head<2>() += truth.tail<2>() * t + a * t * t / 2.0;
      truth.tail<2>() += a * t;
      updater.Predict(f, t);
      updater.Update(f, {truth.head<2>() + sigma_r * Eigen::Vector2d(n(engine), n(engine)), r}, t);
      if (k < 10) continue;  // past the start-up
      const K2::State e = f.x - truth;
      sum += e.dot(f.p.ldlt().solve(e));
      ++count;
    }
  }
  return sum / count;
}

TEST(Updater, TheFilterIsConsistentOnItsOwnModel) {
  // 200 runs x 51 scans: the mean NEES of a consistent filter is 4 +- ~0.1 (its spread is
  // inflated by the scans' correlation); 3.7 .. 4.3 is the usual 95% band for such runs.
  const double kalman = MeanNees(FilterForm::kKalman, 1);
  EXPECT_GT(kalman, 3.7);
  EXPECT_LT(kalman, 4.3);
  // Frozen at the limit of the same recursion, the steady-state form is as consistent.
  const double steady = MeanNees(FilterForm::kSteadyState, 1);
  std::printf("mean NEES: Kalman %.3f, steady state %.3f\n", kalman, steady);
  EXPECT_GT(steady, 3.7);
  EXPECT_LT(steady, 4.3);
}

TEST(Updater, SteadyStateFreezesAtTheRiccatiLimitAndUnfreezesOnAMissOrANewInterval) {
  const double sigma_a = 3.0, sigma_r = 25.0, t = 60.0 / 33.0;
  const KalmanUpdater<2> updater({sigma_a, FilterForm::kSteadyState, 1e-6});
  const Eigen::Matrix2d r = sigma_r * sigma_r * Eigen::Matrix2d::Identity();
  Eigen::Matrix4d p0 = Eigen::Matrix4d::Identity() * 1e6;
  FilterState<2> f = KalmanUpdater<2>::Start(K2::State::Zero(), p0);
  int scans = 0;
  while (!f.frozen && scans < 500) {
    updater.Predict(f, t);
    updater.Update(f, {Eigen::Vector2d::Zero(), r}, t);
    ++scans;
  }
  ASSERT_TRUE(f.frozen);
  // Per axis the limit is Kalata's alpha-beta (steady_state_gain.h).
  const AlphaBeta ab = KalataAlphaBeta(sigma_a, sigma_r, t);
  EXPECT_NEAR(f.frozen_gain(0, 0), ab.alpha, 1e-4 * ab.alpha);
  EXPECT_NEAR(f.frozen_gain(2, 0), ab.beta / t, 1e-4 * ab.beta / t);
  EXPECT_NEAR(f.frozen_gain(1, 1), ab.alpha, 1e-4 * ab.alpha);
  EXPECT_NEAR(f.frozen_gain(0, 1), 0.0, 1e-12);
  // Frozen: a scan is one constant-gain update, covariances fixed.
  const Eigen::Matrix4d updated = f.frozen_updated;
  updater.Predict(f, t);
  EXPECT_EQ(f.p, f.frozen_predicted);
  const K2::State before = f.x;
  updater.Update(f, {Eigen::Vector2d(10.0, -5.0), r}, t);
  EXPECT_EQ(f.p, updated);
  EXPECT_EQ(f.x, before + f.frozen_gain * (Eigen::Vector2d(10.0, -5.0) - before.head<2>()));
  EXPECT_TRUE(f.frozen);
  // Another scan interval: the full recursion again.
  updater.Predict(f, 1.1 * t);
  EXPECT_FALSE(f.frozen);
  // A miss unfreezes too, and forgets the previous gain (two updates are needed to freeze).
  FilterState<2> g = f;
  g.frozen = true;
  KalmanUpdater<2>::Miss(g);
  EXPECT_FALSE(g.frozen);
  EXPECT_FALSE(g.have_last_gain);
}

TEST(Updater, TheKalmanFormNeverFreezes) {
  const KalmanUpdater<2> updater({3.0, FilterForm::kKalman, 1e-3});
  FilterState<2> f = KalmanUpdater<2>::Start(K2::State::Zero(), Eigen::Matrix4d::Identity() * 1e4);
  for (int k = 0; k < 200; ++k) {
    updater.Predict(f, 1.0);
    updater.Update(f, {Eigen::Vector2d::Zero(), 100.0 * Eigen::Matrix2d::Identity()}, 1.0);
  }
  EXPECT_FALSE(f.frozen);
}

}  // namespace
}  // namespace localizer::engine::tws
