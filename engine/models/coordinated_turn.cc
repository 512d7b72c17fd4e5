#include "engine/models/coordinated_turn.h"

#include <cmath>

#include "engine/models/constant_velocity.h"

namespace localizer::engine {
namespace {

// The turn's coefficients and their derivatives in omega:
//   a = sin(w T) / w,  b = (1 - cos(w T)) / w,  da = d a / d w,  db = d b / d w.
struct TurnTerms {
  double s = 0, c = 0, a = 0, b = 0, da = 0, db = 0;
};

TurnTerms Terms(double w, double t) {
  TurnTerms k;
  k.s = std::sin(w * t);
  k.c = std::cos(w * t);
  const double u = w * t, u2 = u * u;
  if (std::abs(u) < 1e-2) {  // series: the closed forms cancel here; next terms ~u^6/5040
    k.a = t * (1.0 - u2 / 6.0 + u2 * u2 / 120.0);
    k.b = 0.5 * w * t * t * (1.0 - u2 / 12.0 + u2 * u2 / 360.0);
    k.da = -w * t * t * t / 3.0 * (1.0 - u2 / 10.0);
    k.db = 0.5 * t * t * (1.0 - u2 / 4.0 + u2 * u2 / 72.0);
  } else {
    k.a = k.s / w;
    k.b = (1.0 - k.c) / w;
    k.da = (t * k.c * w - k.s) / (w * w);
    k.db = (t * k.s * w - (1.0 - k.c)) / (w * w);
  }
  return k;
}

}  // namespace

Eigen::VectorXd CoordinatedTurnModel::Propagate(const Eigen::VectorXd& x, double dt_s) const {
  const double t = dt_s;
  const double vx = x(3), vy = x(4), w = x(6);
  const TurnTerms k = Terms(w, t);
  Eigen::VectorXd y = x;
  y(0) = x(0) + k.a * vx - k.b * vy;
  y(1) = x(1) + k.b * vx + k.a * vy;
  y(2) = x(2) + x(5) * t;
  y(3) = k.c * vx - k.s * vy;
  y(4) = k.s * vx + k.c * vy;
  return y;
}

Eigen::MatrixXd CoordinatedTurnModel::Jacobian(const Eigen::VectorXd& x, double dt_s) const {
  const double t = dt_s;
  const double vx = x(3), vy = x(4), w = x(6);
  const TurnTerms k = Terms(w, t);
  Eigen::MatrixXd f = Eigen::MatrixXd::Identity(7, 7);
  f(0, 3) = k.a;
  f(0, 4) = -k.b;
  f(1, 3) = k.b;
  f(1, 4) = k.a;
  f(2, 5) = t;
  f(3, 3) = k.c;
  f(3, 4) = -k.s;
  f(4, 3) = k.s;
  f(4, 4) = k.c;
  f(0, 6) = k.da * vx - k.db * vy;
  f(1, 6) = k.db * vx + k.da * vy;
  f(3, 6) = -t * k.s * vx - t * k.c * vy;
  f(4, 6) = t * k.c * vx - t * k.s * vy;
  return f;
}

Eigen::MatrixXd CoordinatedTurnModel::ProcessNoise(const Eigen::VectorXd& /*x*/, double dt_s) const {
  const double t = dt_s;
  Eigen::MatrixXd q = Eigen::MatrixXd::Zero(7, 7);
  q.topLeftCorner<6, 6>() = ConstantVelocity{accel_noise_}.ProcessNoise(t);
  q(6, 6) = turn_noise_ * turn_noise_ * t;
  return q;
}

}  // namespace localizer::engine
