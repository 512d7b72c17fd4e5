#include "engine/filters/model_switching.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace localizer::engine {

Status ValidateStayProbability(double stay_probability, const char* field) {
  if (stay_probability >= 0.0 && stay_probability <= 1.0) return Status::Ok();
  return InvalidArgument(std::string(field) + " must be in [0, 1], got " + std::to_string(stay_probability));
}

Eigen::MatrixXd SwitchingMatrix(int model_count, double stay_probability) {
  if (model_count <= 1) return Eigen::MatrixXd::Ones(1, 1);
  const double move = (1.0 - stay_probability) / (model_count - 1);
  Eigen::MatrixXd pi = Eigen::MatrixXd::Constant(model_count, model_count, move);
  pi.diagonal().setConstant(stay_probability);
  return pi;
}

Eigen::VectorXd PredictModelProbabilities(const Eigen::MatrixXd& switching, const Eigen::VectorXd& mu) {
  return switching.transpose() * mu;
}

bool UpdateModelProbabilities(const std::vector<double>& log_likelihoods, Eigen::VectorXd* mu) {
  const int k = static_cast<int>(mu->size());
  // Shift by the largest log L among hypotheses that still have mass, then exponentiate.
  double top = -std::numeric_limits<double>::infinity();
  for (int i = 0; i < k; ++i) {
    if ((*mu)(i) > 0.0 && std::isfinite(log_likelihoods[i])) top = std::max(top, log_likelihoods[i]);
  }
  if (!std::isfinite(top)) return false;
  Eigen::VectorXd posterior(k);
  for (int i = 0; i < k; ++i) {
    posterior(i) = std::isfinite(log_likelihoods[i]) ? (*mu)(i)*std::exp(log_likelihoods[i] - top) : 0.0;
  }
  const double total = posterior.sum();
  if (!(total > 0.0) || !std::isfinite(total)) return false;
  *mu = posterior / total;
  return true;
}

}  // namespace localizer::engine
