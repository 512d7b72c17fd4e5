// The posterior CRLB recursion (engine/filters/posterior_crlb.h) against closed forms.
#include "engine/filters/posterior_crlb.h"

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <random>

#include "engine/models/constant_velocity.h"

namespace localizer::engine {
namespace {

ArrayGeometry Tetrahedron() {
  return *ArrayGeometry::Create({Vec3(1, 1, 1), Vec3(1, -1, -1), Vec3(-1, 1, -1), Vec3(-1, -1, 1)}, 1500.0);
}

// A random walk on all six states: F = I, Q = q I (invertible Q, so Tichavsky's D-form
// can be evaluated as written).
class RandomWalk final : public MotionModel {
 public:
  explicit RandomWalk(double q) : q_(q) {}
  const char* name() const override { return "walk"; }
  int state_dim() const override { return 6; }
  Eigen::VectorXd Propagate(const Eigen::VectorXd& x, double) const override { return x; }
  Eigen::MatrixXd Jacobian(const Eigen::VectorXd&, double) const override { return Eigen::MatrixXd::Identity(6, 6); }
  Eigen::MatrixXd ProcessNoise(const Eigen::VectorXd&, double dt_s) const override {
    return q_ * dt_s * Eigen::MatrixXd::Identity(6, 6);
  }

 private:
  double q_;
};

std::vector<TrueState> StraightLine(const MotionModel& model, int steps, double dt_s,
                                    const Vec3& start_m = Vec3(20.0, -5.0, 3.0),
                                    const Vec3& velocity_mps = Vec3(1.0, 0.5, 0.0)) {
  std::vector<TrueState> truth;
  Eigen::VectorXd x = model.FromPositionVelocity(start_m, velocity_mps);
  for (int k = 0; k < steps; ++k) {
    truth.push_back({k * dt_s, x});
    x.head<3>() += dt_s * velocity_mps;
  }
  return truth;
}

TEST(PosteriorCrlb, MatchesTichavskysInformationFormWhenQIsInvertible) {
  const ArrayGeometry array = Tetrahedron();
  const RandomWalk model(0.3);
  const auto truth = StraightLine(model, 30, 0.1);
  const Eigen::VectorXd sigma = Eigen::VectorXd::Constant(3, 20e-6);
  Eigen::MatrixXd j = TdoaInformation(array, truth[0].state, sigma) + Eigen::MatrixXd::Identity(6, 6) * 0.25;
  const auto bounds = PosteriorCrlb(array, model, truth, sigma, j);
  ASSERT_TRUE(bounds.ok()) << bounds.status().ToString();
  ASSERT_EQ(bounds->size(), truth.size());
  for (size_t k = 1; k < truth.size(); ++k) {
    const Eigen::MatrixXd f = Eigen::MatrixXd::Identity(6, 6);
    const Eigen::MatrixXd q_inv = model.ProcessNoise(truth[k].state, 0.1).inverse();
    const Eigen::MatrixXd d11 = f.transpose() * q_inv * f;
    const Eigen::MatrixXd d12 = -f.transpose() * q_inv;
    const Eigen::MatrixXd d22 = q_inv + TdoaInformation(array, truth[k].state, sigma);
    j = d22 - d12.transpose() * (j + d11).inverse() * d12;
    const Eigen::MatrixXd expected = j.inverse();
    EXPECT_LT(((*bounds)[k] - expected).norm(), 1e-9 * expected.norm()) << "step " << k;
  }
}

TEST(PosteriorCrlb, WithoutProcessNoiseEqualsTheBatchBound) {
  // Q = 0 and deterministic CV motion: the bound is the batch (all frames) Fisher
  // information carried to the last step, J_K = Phi^-T (J_0 + sum_j Phi_j^T I_j Phi_j) Phi^-1.
  const ArrayGeometry array = Tetrahedron();
  const ConstantVelocityModel model(0.0);
  const double dt_s = 0.2;
  const auto truth = StraightLine(model, 25, dt_s);
  const Eigen::VectorXd sigma = Eigen::VectorXd::Constant(3, 10e-6);
  const Eigen::MatrixXd j0 = TdoaInformation(array, truth[0].state, sigma) + Eigen::MatrixXd::Identity(6, 6);
  const auto bounds = PosteriorCrlb(array, model, truth, sigma, j0);
  ASSERT_TRUE(bounds.ok()) << bounds.status().ToString();
  const int last = static_cast<int>(truth.size()) - 1;
  Eigen::MatrixXd total = j0;  // information about the initial state
  for (int k = 1; k <= last; ++k) {
    const Eigen::MatrixXd phi = model.Jacobian(truth[0].state, k * dt_s);
    total += phi.transpose() * TdoaInformation(array, truth[k].state, sigma) * phi;
  }
  const Eigen::MatrixXd phi_last = model.Jacobian(truth[0].state, last * dt_s);
  const Eigen::MatrixXd expected = phi_last * total.inverse() * phi_last.transpose();
  EXPECT_LT(((*bounds)[last] - expected).norm(), 1e-6 * expected.norm());
}

TEST(PosteriorCrlb, ScalesWithTheTdoaVarianceAndMeasurementsAlwaysHelp) {
  const ArrayGeometry array = Tetrahedron();
  const ConstantVelocityModel model(0.0);
  const auto truth = StraightLine(model, 40, 0.1);
  const Eigen::VectorXd sigma = Eigen::VectorXd::Constant(3, 10e-6);
  const Eigen::MatrixXd j0 = TdoaInformation(array, truth[0].state, sigma) + Eigen::MatrixXd::Identity(6, 6);
  // Twice the noise, a quarter of the information everywhere: four times the bound.
  const auto one = PosteriorCrlb(array, model, truth, sigma, j0);
  const auto two = PosteriorCrlb(array, model, truth, 2.0 * sigma, 0.25 * j0);
  ASSERT_TRUE(one.ok() && two.ok());
  for (size_t k = 0; k < truth.size(); ++k) {
    EXPECT_NEAR((*two)[k].trace() / (*one)[k].trace(), 4.0, 1e-6) << "step " << k;
    // Below what the prior alone, carried forward, would allow (20 m out, the range is
    // poorly observed, so the position bound itself may grow while velocity is learnt).
    const Eigen::MatrixXd phi = model.Jacobian(truth[0].state, truth[k].t_s);
    const Eigen::MatrixXd prior_only = phi * j0.inverse() * phi.transpose();
    if (k > 0) {
      EXPECT_LT(((*one)[k].topLeftCorner<3, 3>().trace()), (prior_only.topLeftCorner<3, 3>().trace()));
    }
  }
}

TEST(PosteriorCrlb, ProcessNoiseKeepsTheBoundFromVanishing) {
  const ArrayGeometry array = Tetrahedron();
  const ConstantVelocityModel quiet(0.0), noisy(1.0);
  const auto truth = StraightLine(quiet, 200, 0.1, Vec3(4.0, -2.0, 1.0), Vec3::Zero());
  const Eigen::VectorXd sigma = Eigen::VectorXd::Constant(3, 10e-6);
  const Eigen::MatrixXd j0 = TdoaInformation(array, truth[0].state, sigma) + Eigen::MatrixXd::Identity(6, 6);
  const auto a = PosteriorCrlb(array, quiet, truth, sigma, j0);
  const auto b = PosteriorCrlb(array, noisy, truth, sigma, j0);
  ASSERT_TRUE(a.ok() && b.ok());
  const double quiet_late = a->back().topLeftCorner<3, 3>().trace();
  const double noisy_late = b->back().topLeftCorner<3, 3>().trace();
  const double noisy_mid = (*b)[100].topLeftCorner<3, 3>().trace();
  EXPECT_GT(noisy_late, 3.0 * quiet_late);
  // With process noise the bound settles (steady state) instead of shrinking like 1/k.
  EXPECT_NEAR(noisy_late / noisy_mid, 1.0, 0.5) << noisy_late << " " << noisy_mid << " quiet " << quiet_late;
}

TEST(PosteriorCrlb, BadInputsAreInvalidArgument) {
  const ArrayGeometry array = Tetrahedron();
  const ConstantVelocityModel model(1.0);
  const auto truth = StraightLine(model, 5, 0.1);
  const Eigen::VectorXd sigma = Eigen::VectorXd::Constant(3, 10e-6);
  const Eigen::MatrixXd j0 = Eigen::MatrixXd::Identity(6, 6);
  EXPECT_EQ(PosteriorCrlb(array, model, {}, sigma, j0).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(PosteriorCrlb(array, model, truth, Eigen::VectorXd::Constant(2, 1e-5), j0).status().code(),
            StatusCode::kInvalidArgument);
  EXPECT_EQ(PosteriorCrlb(array, model, truth, Eigen::VectorXd::Zero(3), j0).status().code(),
            StatusCode::kInvalidArgument);
  EXPECT_EQ(PosteriorCrlb(array, model, truth, sigma, Eigen::MatrixXd::Identity(7, 7)).status().code(),
            StatusCode::kInvalidArgument);
  auto backwards = truth;
  backwards[3].t_s = 0.0;
  EXPECT_EQ(PosteriorCrlb(array, model, backwards, sigma, j0).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(PosteriorCrlb(array, model, truth, sigma, Eigen::MatrixXd::Zero(6, 6)).status().code(),
            StatusCode::kFailedPrecondition);
}

}  // namespace
}  // namespace localizer::engine
