// Motion models: transitions and process noise against the continuous-time models they
// discretise (Van Loan's matrix-exponential method), the turn's Jacobian against finite
// differences, and the shared contracts (symmetric PSD noise, dt = 0 is the identity).
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <random>
#include <unsupported/Eigen/MatrixFunctions>

#include "engine/models/constant_acceleration.h"
#include "engine/models/constant_velocity.h"
#include "engine/models/coordinated_turn.h"
#include "engine/models/singer.h"

namespace localizer::engine {
namespace {

struct Discrete {
  Eigen::Matrix3d f;
  Eigen::Matrix3d q;
};

// One axis of dx/dt = A x + B w, w white with PSD psd, over t: F = e^{A t} and
// Q = int_0^t e^{A s} B psd B^T e^{A^T s} ds, both from one exponential (Van Loan 1978).
Discrete VanLoan(const Eigen::Matrix3d& a, double psd, double t) {
  Eigen::Matrix<double, 6, 6> m = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Vector3d b(0.0, 0.0, 1.0);
  m.topLeftCorner<3, 3>() = -a * t;
  m.topRightCorner<3, 3>() = psd * b * b.transpose() * t;
  m.bottomRightCorner<3, 3>() = a.transpose() * t;
  const Eigen::Matrix<double, 6, 6> e = m.exp();
  Discrete d;
  d.f = e.bottomRightCorner<3, 3>().transpose();
  d.q = d.f * e.topRightCorner<3, 3>();
  return d;
}

double RelativeError(const Eigen::MatrixXd& got, const Eigen::MatrixXd& want) {
  return (got - want).norm() / want.norm();
}

TEST(Singer, MatchesTheContinuousModelOverManyTimeConstantsAndSteps) {
  // Van Loan's exponential holds e^{alpha T}: the reference itself degrades beyond
  // alpha T ~ 5, so the pairs stop there (the stationary limit is checked below).
  for (double tau : {0.2, 1.0, 5.0, 60.0, 1e4}) {
    for (double t : {0.01, 0.1, 0.4, 1.0}) {
      const double alpha = 1.0 / tau, sigma = 2.0;
      Eigen::Matrix3d a;
      a << 0, 1, 0, 0, 0, 1, 0, 0, -alpha;
      const Discrete want = VanLoan(a, 2.0 * alpha * sigma * sigma, t);
      const SingerModel model(tau, sigma);
      EXPECT_LT(RelativeError(model.AxisTransition(t), want.f), 1e-10) << "tau " << tau << " t " << t;
      EXPECT_LT(RelativeError(model.AxisNoise(t), want.q), 1e-9) << "tau " << tau << " t " << t;
    }
  }
}

TEST(Singer, LongStepsReachTheStationaryAccelerationVarianceAndForgetIt) {
  const double sigma = 1.5;
  const SingerModel model(0.1, sigma);
  // alpha T = 300: the acceleration decorrelates fully and its variance is sigma^2.
  EXPECT_NEAR(model.AxisNoise(30.0)(2, 2), sigma * sigma, 1e-12);
  EXPECT_NEAR(model.AxisTransition(30.0)(2, 2), 0.0, 1e-12);
  // Both branches agree where they meet (alpha T = 0.5).
  const Eigen::Matrix3d below = model.AxisNoise(0.05 * (1 - 1e-12)), above = model.AxisNoise(0.05 * (1 + 1e-12));
  EXPECT_LT(RelativeError(below, above), 1e-9);
}

TEST(ConstantAcceleration, MatchesTheContinuousWhiteJerkModel) {
  for (double t : {0.01, 0.5, 2.0}) {
    Eigen::Matrix3d a;
    a << 0, 1, 0, 0, 0, 1, 0, 0, 0;
    const Discrete want = VanLoan(a, 0.7, t);
    const ConstantAccelerationModel model(0.7);
    const Eigen::VectorXd x = Eigen::VectorXd::Zero(9);
    const Eigen::MatrixXd f = model.Jacobian(x, t), q = model.ProcessNoise(x, t);
    for (int axis = 0; axis < 3; ++axis) {
      Eigen::Matrix3d f_axis, q_axis;
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
          f_axis(i, j) = f(3 * i + axis, 3 * j + axis);
          q_axis(i, j) = q(3 * i + axis, 3 * j + axis);
        }
      }
      EXPECT_LT(RelativeError(f_axis, want.f), 1e-12);
      EXPECT_LT(RelativeError(q_axis, want.q), 1e-10);
    }
    // Axes are independent: nothing couples x with y.
    EXPECT_EQ(q(0, 1), 0.0);
    EXPECT_EQ(f(0, 4), 0.0);
  }
}

TEST(ConstantAcceleration, PropagatesTheKinematics) {
  const ConstantAccelerationModel model(1.0);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(9);
  x << 1, 2, 3, 0.5, -1, 0, 0.2, 0, -9.81;
  const Eigen::VectorXd y = model.Propagate(x, 2.0);
  EXPECT_NEAR(y(0), 1 + 0.5 * 2 + 0.5 * 0.2 * 4, 1e-12);
  EXPECT_NEAR(y(2), 3 - 0.5 * 9.81 * 4, 1e-12);
  EXPECT_NEAR(y(5), -9.81 * 2, 1e-12);
  EXPECT_NEAR(y(6), 0.2, 1e-15);
}

TEST(CoordinatedTurn, JacobianEqualsFiniteDifferences) {
  const CoordinatedTurnModel model(0.5, 0.05);
  std::mt19937_64 rng(11);
  std::normal_distribution<double> n(0.0, 1.0);
  for (double w : {0.0, 1e-9, 0.02, 0.5, -1.3}) {
    for (double t : {0.05, 1.0}) {
      Eigen::VectorXd x(7);
      x << n(rng), n(rng), n(rng), 3 * n(rng), 3 * n(rng), n(rng), w;
      const Eigen::MatrixXd analytic = model.Jacobian(x, t);
      Eigen::MatrixXd numeric(7, 7);
      for (int j = 0; j < 7; ++j) {
        const double h = 1e-6;
        Eigen::VectorXd up = x, down = x;
        up(j) += h;
        down(j) -= h;
        numeric.col(j) = (model.Propagate(up, t) - model.Propagate(down, t)) / (2 * h);
      }
      EXPECT_LT((analytic - numeric).cwiseAbs().maxCoeff(), 1e-6) << "w " << w << " t " << t;
    }
  }
}

TEST(CoordinatedTurn, AFullTurnReturnsToTheStartAtConstantSpeed) {
  const CoordinatedTurnModel model(0.0, 0.0);
  const double w = 0.1, period = 2 * M_PI / w;
  Eigen::VectorXd x(7);
  x << 10, -5, 2, 3, 4, 0.5, w;
  Eigen::VectorXd y = x;
  for (int k = 0; k < 100; ++k) {
    y = model.Propagate(y, period / 100);
    EXPECT_NEAR(std::hypot(y(3), y(4)), 5.0, 1e-9);
  }
  EXPECT_NEAR(y(0), x(0), 1e-8);
  EXPECT_NEAR(y(1), x(1), 1e-8);
  EXPECT_NEAR(y(2), x(2) + 0.5 * period, 1e-8);
  // A quarter turn counter-clockwise turns the velocity (3, 4) into (-4, 3).
  const Eigen::VectorXd q = model.Propagate(x, period / 4);
  EXPECT_NEAR(q(3), -4.0, 1e-9);
  EXPECT_NEAR(q(4), 3.0, 1e-9);
}

TEST(CoordinatedTurn, ZeroTurnRateIsConstantVelocity) {
  const CoordinatedTurnModel ct(0.5, 0.05);
  const ConstantVelocityModel cv(0.5);
  Eigen::VectorXd x(7);
  x << 1, 2, 3, -0.5, 0.25, 1, 0.0;
  EXPECT_LT((ct.Propagate(x, 0.7).head<6>() - cv.Propagate(x.head<6>(), 0.7)).norm(), 1e-14);
  EXPECT_LT((ct.ProcessNoise(x, 0.7).topLeftCorner<6, 6>() - cv.ProcessNoise(x.head<6>(), 0.7)).norm(), 1e-14);
}

TEST(MotionModels, NoiseIsSymmetricPsdAndZeroStepIsTheIdentity) {
  MotionModelOptions o;
  for (const char* name : {"cv", "ca", "ct", "singer"}) {
    const auto kind = ParseMotionModelKind(name, "motion_model");
    ASSERT_TRUE(kind.ok()) << name;
    EXPECT_STREQ(MotionModelKindName(*kind), name);
    auto model = MakeMotionModel(*kind, o);
    ASSERT_TRUE(model.ok()) << name;
    const MotionModel& m = **model;
    EXPECT_STREQ(m.name(), name);
    Eigen::VectorXd x = m.FromPositionVelocity({1, 2, 3}, {4, 5, 6});
    if (m.state_dim() == 7) x(6) = 0.2;
    EXPECT_LT((m.Propagate(x, 0.0) - x).norm(), 1e-12) << name;
    for (double t : {1e-4, 0.1, 2.0}) {
      const Eigen::MatrixXd q = m.ProcessNoise(x, t);
      ASSERT_EQ(q.rows(), m.state_dim());
      EXPECT_LT((q - q.transpose()).norm(), 1e-12 * (1 + q.norm())) << name;
      const Eigen::VectorXd eig = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(q).eigenvalues();
      EXPECT_GE(eig.minCoeff(), -1e-12 * (1 + eig.maxCoeff())) << name << " t " << t;
      EXPECT_GT(eig.maxCoeff(), 0.0) << name;
    }
    if (std::string(name) != "ct") {  // linear models: f(x) = F x
      EXPECT_LT((m.Propagate(x, 0.3) - m.Jacobian(x, 0.3) * x).norm(), 1e-12) << name;
    }
  }
}

TEST(MotionModels, BadNamesAndOptionsAreInvalidArgument) {
  MotionModelOptions o;
  const auto imm = ParseMotionModelKind("imm", "motion_model");
  EXPECT_EQ(imm.status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(imm.status().message(), "motion_model 'imm' is not one of: cv, ca, ct, singer");
  o.singer_tau_s = 0.0;
  EXPECT_EQ(MakeMotionModel(MotionModelKind::kSinger, o).status().code(), StatusCode::kInvalidArgument);
  o = {};
  o.jerk_psd = -1.0;
  EXPECT_EQ(MakeMotionModel(MotionModelKind::kCa, o).status().code(), StatusCode::kInvalidArgument);
  o = {};
  o.accel_noise_mps2 = std::nan("");
  EXPECT_EQ(MakeMotionModel(MotionModelKind::kCv, o).status().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace localizer::engine
