// Constant-velocity Kalman filter in D = 2 or 3 dimensions with fixed-size Eigen types: the
// tracker's predictor and updater (Stone Soup's KalmanPredictor / KalmanUpdater roles).
//
// State x = (p, v), p and v in R^D (m, m/s); covariance P = [A B; B^T C] in D x D blocks.
// Predict over dt with piecewise-constant white acceleration of std sigma_a per axis
// (q = sigma_a^2; Bar-Shalom, Li & Kirubarajan 6.3.2):
//     x' = F x,  F = [I dt I; 0 I];  P' = F P F^T + Q,  Q = q [dt^4/4 I  dt^3/2 I; dt^3/2 I  dt^2 I]
// written by blocks (A' = A + dt (B + B^T) + dt^2 C + q dt^4/4 I, ...): about 1/3 of the
// flops of the dense product.
// Update with a position measurement z = H x + w, H = [I 0], w ~ N(0, R):
//     nu = z - p,  S = A + R,  K = P H^T S^-1 = [A; B^T] S^-1,
//     x <- x + K nu,  P <- P - K S K^T  (symmetrised).
// Steady-state (constant-gain) form: once the gain has converged, x <- F x + K (z - H F x)
// with K and the predicted P frozen: alpha-beta in every axis when R is isotropic.
// Cost per predict + update (D = 2): ~150 flops.
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>

namespace localizer::engine::tws {

template <int D>
struct Cv {
  static constexpr int kN = 2 * D;
  using State = Eigen::Matrix<double, kN, 1>;
  using Cov = Eigen::Matrix<double, kN, kN>;
  using Pos = Eigen::Matrix<double, D, 1>;
  using PosCov = Eigen::Matrix<double, D, D>;
  using Gain = Eigen::Matrix<double, kN, D>;

  static void PredictState(State& x, double dt) { x.template head<D>() += dt * x.template tail<D>(); }

  static void PredictCov(Cov& p, double dt, double q) {
    const PosCov a = p.template topLeftCorner<D, D>();
    const PosCov b = p.template topRightCorner<D, D>();
    const PosCov c = p.template bottomRightCorner<D, D>();
    const double dt2 = dt * dt;
    PosCov a2 = a + dt * (b + b.transpose()) + dt2 * c;
    PosCov b2 = b + dt * c;
    PosCov c2 = c;
    a2.diagonal().array() += q * dt2 * dt2 / 4.0;
    b2.diagonal().array() += q * dt2 * dt / 2.0;
    c2.diagonal().array() += q * dt2;
    p.template topLeftCorner<D, D>() = a2;
    p.template topRightCorner<D, D>() = b2;
    p.template bottomLeftCorner<D, D>() = b2.transpose();
    p.template bottomRightCorner<D, D>() = c2;
  }

  // Full Kalman update; returns the gain used.
  static Gain Update(State& x, Cov& p, const Pos& z, const PosCov& r) {
    const PosCov s = p.template topLeftCorner<D, D>() + r;
    const PosCov s_inv = s.inverse();  // closed form for D <= 3
    const Gain ph = p.template leftCols<D>();
    Gain k = ph * s_inv;  // not const: returned by move
    x += k * (z - x.template head<D>());
    p -= k * ph.transpose();
    p = 0.5 * (p + p.transpose()).eval();
    return k;
  }

  static void UpdateConstantGain(State& x, const Gain& k, const Pos& z) { x += k * (z - x.template head<D>()); }
};

}  // namespace localizer::engine::tws
