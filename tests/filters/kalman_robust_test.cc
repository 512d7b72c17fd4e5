// The Kalman filters' robust (Huber, Student-t) update and the hooks the IMM uses: one
// outlier pair moves the robust EKF/UKF far less than the plain one, clean frames update
// alike, a frame with one bad pair is used instead of gated; the update's Gaussian
// log-likelihood against the formula; SetState's checks.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <numbers>
#include <random>

#include "engine/filters/kalman_filter.h"
#include "tests/filters/manoeuvre_track.h"

namespace localizer::engine {
namespace {

constexpr double kSigma = 2e-6;
const Vec3 kSource(4.0, 4.0, 0.0);

// The TDOAs of a source at rest at p with N(0, sigma^2) noise, every pair usable.
Measurement StillTdoas(const ArrayGeometry& array, const Vec3& p, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, kSigma);
  const Eigen::VectorXd t = array.Tdoa(p);
  Measurement m;
  m.sample_rate_hz = 48000.0;
  for (int k = 0; k < array.pair_count(); ++k) {
    PairMeasurement pair;
    pair.sensor = array.sensor_of_pair(k);
    pair.delay_s = t(k) + noise(rng);
    pair.peak_snr = 50.0;
    m.pairs.push_back(pair);
  }
  return m;
}

// A held track: the prior is 2 cm off the source with 2 cm / 1 cm/s stds.
std::unique_ptr<KalmanFilter> Held(const ArrayGeometry& array, RobustUpdate robust, double gate_probability,
                                   KalmanVariant variant = KalmanVariant::kExtended) {
  KalmanOptions o;
  o.variant = variant;
  o.tdoa_sigma_s = kSigma;
  o.robust = robust;
  o.gate_probability = gate_probability;
  auto filter = std::move(*KalmanFilter::Create(array, o));
  TrackState belief;
  belief.mean.head<3>() = kSource + Vec3(0.02, -0.02, 0.02);
  belief.covariance.topLeftCorner<3, 3>() = 4e-4 * Mat3::Identity();
  belief.covariance.bottomRightCorner<3, 3>() = 1e-4 * Mat3::Identity();
  EXPECT_TRUE(filter->Initialise(belief).ok());
  return filter;
}

double ErrorAfter(KalmanFilter& filter, const Measurement& m) {
  EXPECT_TRUE(filter.Update(m).ok());
  return (filter.mean().head<3>() - kSource).norm();
}

TEST(KalmanRobust, OneOutlierPairMovesTheHuberFilterFarLess) {
  const ArrayGeometry array = testing::BoxArray();
  for (auto variant : {KalmanVariant::kExtended, KalmanVariant::kUnscented}) {
    for (uint64_t seed : {1, 2, 3}) {
      const Measurement clean = StillTdoas(array, kSource, seed);
      Measurement bad = clean;
      bad.pairs[2].delay_s += 50 * kSigma;  // one pair locked on a reflection
      // No gate: the plain filter takes the outlier at full weight.
      const double plain_clean = ErrorAfter(*Held(array, RobustUpdate::kNone, 1.0, variant), clean);
      const double plain_bad = ErrorAfter(*Held(array, RobustUpdate::kNone, 1.0, variant), bad);
      const double huber_clean = ErrorAfter(*Held(array, RobustUpdate::kHuber, 1.0, variant), clean);
      const double huber_bad = ErrorAfter(*Held(array, RobustUpdate::kHuber, 1.0, variant), bad);
      const double t_clean = ErrorAfter(*Held(array, RobustUpdate::kStudentT, 1.0, variant), clean);
      const double t_bad = ErrorAfter(*Held(array, RobustUpdate::kStudentT, 1.0, variant), bad);
      std::printf(
          "seed %d %s: error after a clean frame plain %.4f huber %.4f student-t %.4f m; with one 50-sigma "
          "pair plain %.4f huber %.4f student-t %.4f m\n",
          static_cast<int>(seed), variant == KalmanVariant::kExtended ? "ekf" : "ukf", plain_clean, huber_clean,
          t_clean, plain_bad, huber_bad, t_bad);
      // The outlier's pull on the estimate, beyond the clean frame's error (measured: plain
      // 0.08-0.09 m, robust < 0.001 m).
      EXPECT_LT(huber_bad - huber_clean, 0.1 * (plain_bad - plain_clean)) << seed;
      EXPECT_LT(t_bad - t_clean, 0.1 * (plain_bad - plain_clean)) << seed;
      // Clean frames: nearly the same update.
      EXPECT_LT(huber_clean, 1.5 * plain_clean + 1e-3) << seed;
      EXPECT_LT(t_clean, 1.5 * plain_clean + 1e-3) << seed;
    }
  }
}

// With the default gate the plain filter drops a frame with one bad pair whole; the robust
// filters gate on the reweighted innovation and use the other pairs: Huber for a moderate
// outlier (8 sigma: plain NIS ~70 > 29.9, the 0.9999 quantile for 7 pairs), Student-t for
// a gross one too (50 sigma).
TEST(KalmanRobust, AFrameWithOneBadPairIsUsedNotGated) {
  const ArrayGeometry array = testing::BoxArray();
  struct Case {
    RobustUpdate robust;
    double outlier_sigmas;
  };
  for (const Case& c :
       {Case{RobustUpdate::kHuber, 8.0}, Case{RobustUpdate::kStudentT, 8.0}, Case{RobustUpdate::kStudentT, 50.0}}) {
    Measurement bad = StillTdoas(array, kSource, 4);
    bad.pairs[5].delay_s -= c.outlier_sigmas * kSigma;
    auto plain = Held(array, RobustUpdate::kNone, 0.9999);
    auto robust = Held(array, c.robust, 0.9999);
    const double prior_error = (plain->mean().head<3>() - kSource).norm();
    const auto plain_report = plain->Update(bad);
    const auto robust_report = robust->Update(bad);
    ASSERT_TRUE(plain_report.ok() && robust_report.ok());
    SCOPED_TRACE(std::to_string(c.outlier_sigmas) + " sigma, robust " + std::to_string(static_cast<int>(c.robust)));
    EXPECT_TRUE(plain_report->gated);
    EXPECT_FALSE(robust_report->gated);
    EXPECT_EQ(robust_report->nis, plain_report->nis);  // the reported NIS stays the plain one
    EXPECT_LT((robust->mean().head<3>() - kSource).norm(), 0.5 * prior_error);
  }
  // Huber's influence is bounded, not redescending: a gross outlier still gates the frame.
  Measurement gross = StillTdoas(array, kSource, 4);
  gross.pairs[5].delay_s -= 50 * kSigma;
  EXPECT_TRUE(Held(array, RobustUpdate::kHuber, 0.9999)->Update(gross)->gated);
}

TEST(KalmanRobust, LogLikelihoodIsTheGaussianOfTheInnovation) {
  const ArrayGeometry array = testing::BoxArray();
  auto ekf = Held(array, RobustUpdate::kNone, 1.0);
  const Eigen::VectorXd x = ekf->mean();
  const Eigen::MatrixXd p = ekf->covariance();
  const Measurement m = StillTdoas(array, kSource, 5);
  ASSERT_TRUE(ekf->Update(m).ok());
  // By hand, zero prior velocity: h = T(p), H = [J, -(d/2) J].
  const Eigen::MatrixXd j = array.TdoaJacobian(x.head<3>());
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(j.rows(), 6);
  Eigen::VectorXd z(j.rows());
  for (int k = 0; k < j.rows(); ++k) {
    z(k) = m.pairs[k].delay_s;
    h.block(k, 0, 1, 3) = j.row(k);
    h.block(k, 3, 1, 3) = -0.5 * z(k) * j.row(k);
  }
  const Eigen::MatrixXd s = h * p * h.transpose() + kSigma * kSigma * Eigen::MatrixXd::Identity(j.rows(), j.rows());
  const Eigen::VectorXd nu = z - array.Tdoa(x.head<3>());
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(s);
  const double expected = -0.5 * (nu.dot(ldlt.solve(nu)) + ldlt.vectorD().array().log().sum() +
                                  static_cast<double>(j.rows()) * std::log(2.0 * std::numbers::pi));
  EXPECT_NEAR(ekf->last_log_likelihood(), expected, 1e-6 * std::abs(expected));
}

TEST(KalmanRobust, SetStateChecksItsInput) {
  const ArrayGeometry array = testing::BoxArray();
  KalmanOptions o;
  o.motion_model = MotionModelKind::kCt;
  auto ct = std::move(*KalmanFilter::Create(array, o));
  EXPECT_FALSE(ct->initialised());
  EXPECT_STREQ(ct->motion_model_name(), "ct");
  EXPECT_EQ(ct->SetState(Eigen::VectorXd::Zero(6), Eigen::MatrixXd::Identity(6, 6)).code(),
            StatusCode::kInvalidArgument);  // CT has 7 entries
  Eigen::MatrixXd indefinite = Eigen::MatrixXd::Identity(7, 7);
  indefinite(6, 6) = -1.0;
  EXPECT_EQ(ct->SetState(Eigen::VectorXd::Zero(7), indefinite).code(), StatusCode::kInvalidArgument);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(7);
  x << 1, 2, 3, 0.1, 0.2, 0, 0.05;
  ASSERT_TRUE(ct->SetState(x, Eigen::MatrixXd::Identity(7, 7)).ok());
  EXPECT_TRUE(ct->initialised());
  EXPECT_EQ(ct->mean(), x);
  KalmanOptions bad;
  bad.huber_threshold = 0.0;
  EXPECT_NE(KalmanFilter::Create(array, bad).status().message().find("huber_threshold"), std::string::npos);
  EXPECT_EQ(ParseRobustUpdate("huber", "robust").value(), RobustUpdate::kHuber);
  EXPECT_EQ(ParseRobustUpdate("student-t", "robust").value(), RobustUpdate::kStudentT);
  EXPECT_NE(ParseRobustUpdate("tukey", "robust").status().message().find("robust"), std::string::npos);
  EXPECT_STREQ(RobustUpdateName(RobustUpdate::kStudentT), "student-t");
  bad = {};
  bad.student_dof = -1.0;
  EXPECT_NE(KalmanFilter::Create(array, bad).status().message().find("student_dof"), std::string::npos);
}

}  // namespace
}  // namespace localizer::engine
