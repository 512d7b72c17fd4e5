// The steady-state (constant-gain) filter: its gain is the limit of the Riccati recursion
// (Kalata's alpha-beta for one axis), and the tracker in that form follows the seed's case.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>

#include "engine/sim/radar_scan.h"
#include "engine/tws/cv_kalman.h"
#include "engine/tws/steady_state_gain.h"
#include "engine/tws/tws_tracker.h"

namespace localizer::engine::tws {
namespace {

constexpr double kPeriod = 60.0 / 33.0;  // the seed's scan period

TEST(SteadyState, GainEqualsKalataAlphaBeta) {
  for (double sigma_a : {0.1, 1.0, 10.0}) {
    const double sigma_w = 20.0, t = kPeriod, q = sigma_a * sigma_a;
    Eigen::MatrixXd f(2, 2), qm(2, 2), h(1, 2), r(1, 1);
    f << 1, t, 0, 1;
    qm << q * t * t * t * t / 4, q * t * t * t / 2, q * t * t * t / 2, q * t * t;
    h << 1, 0;
    r << sigma_w * sigma_w;
    const SteadyStateResult ss = SteadyStateKalman(f, qm, h, r);
    ASSERT_TRUE(ss.converged);
    const AlphaBeta ab = KalataAlphaBeta(sigma_a, sigma_w, t);
    EXPECT_NEAR(ss.gain(0, 0), ab.alpha, 1e-9 + 1e-6 * ab.alpha) << sigma_a;
    EXPECT_NEAR(ss.gain(1, 0), ab.beta / t, 1e-9 + 1e-6 * ab.beta / t) << sigma_a;
    // The closed loop is stable: spectral radius < 1.
    EXPECT_LT(ss.closed_loop.eigenvalues().cwiseAbs().maxCoeff(), 1.0);
  }
}

TEST(SteadyState, TrackerRecursionConvergesToTheSteadyStateGain) {
  // The tracker's own predictor/updater (cv_kalman.h) iterated with a fixed R.
  const double q = 4.0, t = kPeriod;
  Eigen::Matrix2d r;
  r << 400.0, 150.0, 150.0, 900.0;
  Cv<2>::State x = Cv<2>::State::Zero();
  Cv<2>::Cov p = Cv<2>::Cov::Identity() * 1e6;
  Cv<2>::Gain k;
  for (int i = 0; i < 400; ++i) {
    Cv<2>::PredictCov(p, t, q);
    k = Cv<2>::Update(x, p, Eigen::Vector2d::Zero(), r);
  }
  Eigen::MatrixXd f = Eigen::MatrixXd::Identity(4, 4);
  f.topRightCorner(2, 2) = t * Eigen::MatrixXd::Identity(2, 2);
  Eigen::MatrixXd qm = Eigen::MatrixXd::Zero(4, 4);
  qm.topLeftCorner(2, 2) = q * t * t * t * t / 4 * Eigen::MatrixXd::Identity(2, 2);
  qm.topRightCorner(2, 2) = q * t * t * t / 2 * Eigen::MatrixXd::Identity(2, 2);
  qm.bottomLeftCorner(2, 2) = q * t * t * t / 2 * Eigen::MatrixXd::Identity(2, 2);
  qm.bottomRightCorner(2, 2) = q * t * t * Eigen::MatrixXd::Identity(2, 2);
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(2, 4);
  h.leftCols(2) = Eigen::MatrixXd::Identity(2, 2);
  const SteadyStateResult ss = SteadyStateKalman(f, qm, h, r);
  ASSERT_TRUE(ss.converged);
  EXPECT_LT((Eigen::MatrixXd(k) - ss.gain).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT((Eigen::MatrixXd(p) - ss.updated).cwiseAbs().maxCoeff(), 1e-6 * ss.updated.norm());
}

// The seed's case: one target from (1000 m, 1000 m) at -10 m/s along x, the 33 rpm radar,
// range std 5 m, bearing std 0.005 rad (7 m across at 1.4 km), P_D 1, no clutter.
double RmsError(FilterForm form, int first_scan, int scans, bool* all_frozen) {
  RadarScanOptions radar;
  radar.max_range_m = 10000.0;
  radar.range_sigma_m = 5.0;
  radar.bearing_sigma_rad = 0.005;
  radar.detection_probability = 1.0;
  radar.seed = 42;
  auto sim = RadarScanSimulator::Create(radar, SeedCaseTargets());
  TwsOptions o;
  o.noise.range_sigma_m = radar.range_sigma_m;
  o.noise.bearing_sigma_rad = radar.bearing_sigma_rad;
  o.accel_noise_mps2 = 0.1;
  o.initial_speed_sigma_mps = 20.0;
  o.filter = form;
  auto tracker = TwsTracker::Create(o);
  double sum = 0.0;
  int n = 0;
  *all_frozen = true;
  for (int k = 0; k < scans; ++k) {
    const RadarScanFrame frame = sim->Frame(k);
    EXPECT_TRUE((*tracker)->Process(frame.scan).ok());
    const auto tracks = (*tracker)->Tracks(false);
    if (k < first_scan) continue;
    EXPECT_EQ(tracks.size(), 1u);
    if (tracks.empty()) continue;
    EXPECT_EQ(tracks[0].id, 1u);
    *all_frozen = *all_frozen && tracks[0].steady_state;
    sum += (tracks[0].position_m - frame.truth[0].position_m).squaredNorm();
    ++n;
  }
  return std::sqrt(sum / n);
}

TEST(SteadyState, SeedCaseTrackedWithinStatedError) {
  bool frozen = false, kalman_frozen = true;
  const double steady = RmsError(FilterForm::kSteadyState, 30, 80, &frozen);
  const double kalman = RmsError(FilterForm::kKalman, 30, 80, &kalman_frozen);
  std::printf("rms position error after scan 30: steady-state %.2f m, Kalman %.2f m\n", steady, kalman);
  EXPECT_TRUE(frozen);          // the gain froze by scan 30 (at 22) and stayed frozen
  EXPECT_FALSE(kalman_frozen);  // the Kalman form never freezes
  // Stated error: under 5 m rms (a single plot's error is ~7 m rms here), and within
  // 30 % of the full Kalman filter's (R turns with the bearing; the frozen gain does not).
  EXPECT_LT(steady, 5.0);
  EXPECT_LT(steady, 1.3 * kalman);
}

}  // namespace
}  // namespace localizer::engine::tws
