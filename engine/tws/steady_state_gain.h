// Steady-state Kalman gain: the limit of the Riccati recursion, which the seed's DSP
// implementation pre-computed so that each scan costs one constant-gain update
// x(k+1|k+1) = Phi x(k|k) + K z(k+1), Phi = (I - K H) F.
//
// Riccati recursion from P(0|0) = p0 I (prediction, gain, update):
//     P(k+1|k) = F P(k|k) F^T + Q,  S = H P(k+1|k) H^T + R,  K = P(k+1|k) H^T S^-1,
//     P(k+1|k+1) = (I - K H) P(k+1|k)
// iterated until max |K_k - K_k-1| <= tolerance * max |K_k| (converged = true) or
// max_iterations. For a detectable, stabilisable (F, H, Q^1/2) the limit is unique and
// independent of p0.
// Closed form for one axis of a constant-velocity target with piecewise-constant white
// acceleration (Kalata 1984): tracking index lambda = sigma_a T^2 / sigma_w,
//     r = (4 + lambda - sqrt(8 lambda + lambda^2)) / 4,  alpha = 1 - r^2,
//     beta = 2 (2 - alpha) - 4 sqrt(1 - alpha);  K = (alpha, beta / T).
#pragma once

#include <Eigen/Core>

namespace localizer::engine::tws {

struct SteadyStateResult {
  Eigen::MatrixXd gain;         // K, n x m
  Eigen::MatrixXd predicted;    // P(k+1|k) in the limit
  Eigen::MatrixXd updated;      // P(k+1|k+1) in the limit
  Eigen::MatrixXd closed_loop;  // Phi = (I - K H) F
  int iterations = 0;
  bool converged = false;
};

SteadyStateResult SteadyStateKalman(const Eigen::MatrixXd& f, const Eigen::MatrixXd& q, const Eigen::MatrixXd& h,
                                    const Eigen::MatrixXd& r, double tolerance = 1e-12, int max_iterations = 100000,
                                    double initial_variance = 1e6);

struct AlphaBeta {
  double alpha = 0.0;
  double beta = 0.0;
};
// Kalata's closed form; sigma_a: acceleration std (m/s^2), sigma_w: measurement std (m).
AlphaBeta KalataAlphaBeta(double sigma_a, double sigma_w, double period_s);

}  // namespace localizer::engine::tws
