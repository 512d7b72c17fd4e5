#include "engine/filters/posterior_crlb.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <string>

namespace localizer::engine {
namespace {

// Inverse of a symmetric positive definite matrix, or FAILED_PRECONDITION naming `what`.
StatusOr<Eigen::MatrixXd> InverseSpd(const Eigen::MatrixXd& m, const std::string& what) {
  const Eigen::MatrixXd sym = 0.5 * (m + m.transpose());
  Eigen::LDLT<Eigen::MatrixXd> ldlt(sym);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive() || ldlt.vectorD().minCoeff() <= 0.0) {
    return FailedPrecondition(what + " is not positive definite");
  }
  Eigen::MatrixXd inverse = ldlt.solve(Eigen::MatrixXd::Identity(m.rows(), m.cols()));
  return Eigen::MatrixXd(0.5 * (inverse + inverse.transpose()));
}

}  // namespace

Eigen::MatrixXd TdoaInformation(const ArrayGeometry& array, const Eigen::VectorXd& state,
                                const Eigen::VectorXd& sigma_s) {
  const Eigen::Index n = state.size();
  const Vec3 p = state.head<3>();
  const Eigen::VectorXd delay_s = array.Tdoa(p);
  const Eigen::MatrixXd grad = array.TdoaJacobian(p);  // pairs x 3, s/m
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(grad.rows(), n);
  h.leftCols(3) = grad;
  for (Eigen::Index k = 0; k < grad.rows(); ++k) h.row(k).segment(3, 3) = -0.5 * delay_s(k) * grad.row(k);
  const Eigen::VectorXd inv_var = sigma_s.array().square().inverse();
  return h.transpose() * inv_var.asDiagonal() * h;
}

StatusOr<std::vector<Eigen::MatrixXd>> PosteriorCrlb(const ArrayGeometry& array, const MotionModel& model,
                                                     const std::vector<TrueState>& truth,
                                                     const Eigen::VectorXd& sigma_s,
                                                     const Eigen::MatrixXd& initial_information) {
  const int n = model.state_dim();
  if (truth.empty()) return InvalidArgument("PCRLB truth is empty");
  if (sigma_s.size() != array.pair_count() || !(sigma_s.array() > 0.0).all() || !sigma_s.allFinite()) {
    return InvalidArgument("PCRLB sigma_s needs " + std::to_string(array.pair_count()) +
                           " finite positive entries (one per pair)");
  }
  if (initial_information.rows() != n || initial_information.cols() != n) {
    return InvalidArgument("PCRLB initial_information must be " + std::to_string(n) + " x " + std::to_string(n));
  }
  for (size_t k = 0; k < truth.size(); ++k) {
    if (truth[k].state.size() != n || !truth[k].state.allFinite()) {
      return InvalidArgument("PCRLB truth[" + std::to_string(k) + "] state must have " + std::to_string(n) +
                             " finite entries (" + model.name() + ")");
    }
    if (k > 0 && !(truth[k].t_s >= truth[k - 1].t_s)) {
      return InvalidArgument("PCRLB truth[" + std::to_string(k) + "] time goes backwards");
    }
  }
  std::vector<Eigen::MatrixXd> bounds;
  bounds.reserve(truth.size());
  auto cov = InverseSpd(initial_information, "initial information");
  if (!cov.ok()) return cov.status();
  bounds.push_back(*cov);
  for (size_t k = 1; k < truth.size(); ++k) {
    const double dt_s = truth[k].t_s - truth[k - 1].t_s;
    const Eigen::MatrixXd f = model.Jacobian(truth[k - 1].state, dt_s);
    const Eigen::MatrixXd q = model.ProcessNoise(truth[k - 1].state, dt_s);
    // Predicted bound F J^-1 F^T + Q, then the measurement's information added.
    const Eigen::MatrixXd predicted = f * bounds.back() * f.transpose() + q;
    auto prior_info = InverseSpd(predicted, "predicted bound at step " + std::to_string(k));
    if (!prior_info.ok()) return prior_info.status();
    auto next = InverseSpd(*prior_info + TdoaInformation(array, truth[k].state, sigma_s),
                           "information at step " + std::to_string(k));
    if (!next.ok()) return next.status();
    bounds.push_back(std::move(next).value());
  }
  return bounds;
}

}  // namespace localizer::engine
