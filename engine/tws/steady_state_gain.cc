#include "engine/tws/steady_state_gain.h"

#include <Eigen/LU>
#include <cmath>

namespace localizer::engine::tws {

SteadyStateResult SteadyStateKalman(const Eigen::MatrixXd& f, const Eigen::MatrixXd& q, const Eigen::MatrixXd& h,
                                    const Eigen::MatrixXd& r, double tolerance, int max_iterations,
                                    double initial_variance) {
  const auto n = f.rows();
  const Eigen::MatrixXd identity = Eigen::MatrixXd::Identity(n, n);
  SteadyStateResult out;
  Eigen::MatrixXd p = initial_variance * identity;
  Eigen::MatrixXd previous = Eigen::MatrixXd::Zero(n, h.rows());
  for (int k = 1; k <= max_iterations; ++k) {
    const Eigen::MatrixXd predicted = f * p * f.transpose() + q;
    const Eigen::MatrixXd s = h * predicted * h.transpose() + r;
    const Eigen::MatrixXd gain = predicted * h.transpose() * s.inverse();
    p = (identity - gain * h) * predicted;
    p = 0.5 * (p + p.transpose()).eval();
    out.gain = gain;
    out.predicted = predicted;
    out.updated = p;
    out.iterations = k;
    if (k > 1 && (gain - previous).cwiseAbs().maxCoeff() <= tolerance * gain.cwiseAbs().maxCoeff()) {
      out.converged = true;
      break;
    }
    previous = gain;
  }
  out.closed_loop = (identity - out.gain * h) * f;
  return out;
}

AlphaBeta KalataAlphaBeta(double sigma_a, double sigma_w, double period_s) {
  const double lambda = sigma_a * period_s * period_s / sigma_w;
  const double r = (4.0 + lambda - std::sqrt(8.0 * lambda + lambda * lambda)) / 4.0;
  AlphaBeta ab;
  ab.alpha = 1.0 - r * r;
  ab.beta = 2.0 * (2.0 - ab.alpha) - 4.0 * std::sqrt(1.0 - ab.alpha);
  return ab;
}

}  // namespace localizer::engine::tws
