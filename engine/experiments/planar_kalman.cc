#include "engine/experiments/planar_kalman.h"

#include <Eigen/Cholesky>
#include <Eigen/Dense>
#include <cmath>
#include <string>

#include "engine/sim/invalid_value.h"

namespace localizer::engine::experiments {
namespace {

using Mat2 = Eigen::Matrix2d;
using Mat3 = Eigen::Matrix3d;
using Mat23 = Eigen::Matrix<double, 2, 3>;
using Mat32 = Eigen::Matrix<double, 3, 2>;

constexpr int kAugmented = 5;  // (x, y, theta, w_v, w_d)
constexpr int kMaxReweightings = 10;
constexpr double kConvergedM = 1e-9;

bool NonNegativeFinite(double value) { return value >= 0.0 && std::isfinite(value); }
bool PositiveFinite(double value) { return value > 0.0 && std::isfinite(value); }

Mat2 ControlCovariance(const ControlNoise& noise) {
  return Eigen::Vector2d(noise.speed_sigma_mps * noise.speed_sigma_mps,
                         noise.steering_sigma_rad * noise.steering_sigma_rad)
      .asDiagonal();
}

PlanarBelief PredictExtended(const PlanarBelief& prior, const BicycleModel& model, const Mat2& control_covariance,
                             const BicycleControl& u, double dt_s) {
  const Mat3 f = model.StateJacobian(prior.mean, u, dt_s);
  const Mat32 g = model.ControlJacobian(prior.mean, u, dt_s);
  PlanarBelief next;
  next.mean = model.Step(prior.mean, u, dt_s);
  next.covariance = f * prior.covariance * f.transpose() + g * control_covariance * g.transpose();
  return next;
}

// Scaled sigma points with alpha 1, beta 2, kappa 0 over the augmented state.
PlanarBelief PredictUnscented(const PlanarBelief& prior, const BicycleModel& model, const Mat2& control_covariance,
                              const BicycleControl& u, double dt_s) {
  Eigen::Matrix<double, kAugmented, kAugmented> p = Eigen::Matrix<double, kAugmented, kAugmented>::Zero();
  p.topLeftCorner<3, 3>() = prior.covariance;
  p.bottomRightCorner<2, 2>() = control_covariance;
  // LDLT tolerates the semi-definite covariances a zero noise term gives.
  const Eigen::LDLT<Eigen::Matrix<double, kAugmented, kAugmented>> ldlt(p);
  Eigen::Matrix<double, kAugmented, kAugmented> root = ldlt.transpositionsP().transpose() *
                                                       Eigen::Matrix<double, kAugmented, kAugmented>(ldlt.matrixL()) *
                                                       ldlt.vectorD().cwiseMax(0.0).cwiseSqrt().asDiagonal();
  root *= std::sqrt(static_cast<double>(kAugmented));  // sqrt(n + lambda), lambda = 0
  const auto propagate = [&](const Eigen::Matrix<double, kAugmented, 1>& a) {
    return model.Step(a.head<3>(), {u.speed_mps + a[3], u.steering_rad + a[4]}, dt_s);
  };
  Eigen::Matrix<double, kAugmented, 1> centre;
  centre << prior.mean, 0.0, 0.0;
  const PlanarState y0 = propagate(centre);
  PlanarState y[2 * kAugmented];
  PlanarState mean = PlanarState::Zero();
  const double w = 0.5 / kAugmented;  // 1 / (2 (n + lambda)); the centre's mean weight is 0
  for (int i = 0; i < kAugmented; ++i) {
    y[2 * i] = propagate(centre + root.col(i));
    y[2 * i + 1] = propagate(centre - root.col(i));
    mean += w * (y[2 * i] + y[2 * i + 1]);
  }
  PlanarBelief next;
  next.mean = mean;
  next.covariance = 2.0 * (y0 - mean) * (y0 - mean).transpose();  // 1 - alpha^2 + beta
  for (const PlanarState& yi : y) next.covariance += w * (yi - mean) * (yi - mean).transpose();
  return next;
}

// The Gaussian update with R = diag(variance_m2), Joseph form.
PlanarBelief KalmanUpdate(const PlanarBelief& prior, const Eigen::Vector2d& z, const Eigen::Vector2d& variance_m2) {
  Mat23 h = Mat23::Zero();
  h(0, kPx) = 1.0;
  h(1, kPy) = 1.0;
  const Mat2 r = variance_m2.asDiagonal();
  const Mat2 s = h * prior.covariance * h.transpose() + r;
  const Mat32 k = prior.covariance * h.transpose() * s.inverse();
  const Mat3 i_kh = Mat3::Identity() - k * h;
  PlanarBelief post;
  post.mean = prior.mean + k * (z - h * prior.mean);
  post.covariance = i_kh * prior.covariance * i_kh.transpose() + k * r * k.transpose();
  post.covariance = 0.5 * (post.covariance + post.covariance.transpose()).eval();
  return post;
}

}  // namespace

Status ControlNoise::Validate() const {
  if (!NonNegativeFinite(speed_sigma_mps)) {
    return sim_detail::Invalid("speed_sigma_mps", speed_sigma_mps, "must be >= 0 and finite");
  }
  if (!NonNegativeFinite(steering_sigma_rad)) {
    return sim_detail::Invalid("steering_sigma_rad", steering_sigma_rad, "must be >= 0 and finite");
  }
  return Status::Ok();
}

Status PlanarKalmanOptions::Validate() const {
  if (!PositiveFinite(measurement_sigma_m)) {
    return sim_detail::Invalid("measurement_sigma_m", measurement_sigma_m, "must be positive and finite");
  }
  if (!PositiveFinite(huber_threshold)) {
    return sim_detail::Invalid("huber_threshold", huber_threshold, "must be positive and finite");
  }
  if (!PositiveFinite(student_dof)) {
    return sim_detail::Invalid("student_dof", student_dof, "must be positive and finite");
  }
  return Status::Ok();
}

StatusOr<std::unique_ptr<PlanarKalmanFilter>> PlanarKalmanFilter::Create(const BicycleModel& model,
                                                                         const ControlNoise& control_noise,
                                                                         const PlanarKalmanOptions& options) {
  LOCALIZER_RETURN_IF_ERROR(model.Validate());
  LOCALIZER_RETURN_IF_ERROR(control_noise.Validate());
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  return std::unique_ptr<PlanarKalmanFilter>(new PlanarKalmanFilter(model, control_noise, options));
}

void PlanarKalmanFilter::Initialise(const PlanarBelief& belief) { belief_ = belief; }

void PlanarKalmanFilter::Predict(const BicycleControl& command, double dt_s) {
  const Mat2 m = ControlCovariance(control_noise_);
  belief_ = options_.predictor == PlanarPredictor::kExtended ? PredictExtended(belief_, model_, m, command, dt_s)
                                                             : PredictUnscented(belief_, model_, m, command, dt_s);
}

double PlanarKalmanFilter::Weight(double residual) const {
  switch (options_.updater) {
    case PlanarUpdater::kGaussian:
      return 1.0;
    case PlanarUpdater::kHuber:
      return std::min(1.0, options_.huber_threshold / std::abs(residual));
    case PlanarUpdater::kStudentT:
      return (options_.student_dof + 1.0) / (options_.student_dof + residual * residual);
  }
  return 1.0;
}

void PlanarKalmanFilter::Update(const Eigen::Vector2d& z_m) {
  const double sigma = options_.measurement_sigma_m;
  const Eigen::Vector2d variance = Eigen::Vector2d::Constant(sigma * sigma);
  PlanarBelief post = KalmanUpdate(belief_, z_m, variance);
  if (options_.updater != PlanarUpdater::kGaussian) {
    // Reweight from the prior: the first weights see the innovation itself.
    PlanarState estimate = belief_.mean;
    for (int iteration = 0; iteration < kMaxReweightings; ++iteration) {
      const Eigen::Vector2d r = (z_m - estimate.head<2>()) / sigma;
      const Eigen::Vector2d weights(Weight(r.x()), Weight(r.y()));
      post = KalmanUpdate(belief_, z_m, variance.cwiseQuotient(weights));
      const bool converged = (post.mean.head<2>() - estimate.head<2>()).norm() < kConvergedM;
      estimate = post.mean;
      if (converged) break;
    }
  }
  belief_ = post;
}

}  // namespace localizer::engine::experiments
