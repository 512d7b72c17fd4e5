// Singer's manoeuvring-target model (Singer 1970; Li & Jilkov, "Survey of maneuvering target
// tracking, Part I", 2003, eq. 14-16): each axis's acceleration is a first-order Markov
// (Ornstein-Uhlenbeck) process, da/dt = -alpha a + w, alpha = 1 / tau (tau: the manoeuvre
// time constant), with stationary std sigma_m, so the white noise w has PSD 2 alpha sigma_m^2.
// State (p, v, a), 9 entries; per axis, with e = exp(-alpha T):
//     F1 = [1 T (alpha T - 1 + e) / alpha^2; 0 1 (1 - e) / alpha; 0 0 e]
//     Q1 = 2 alpha sigma_m^2 [q_ij], with
//       q11 = (1 - e^2 + 2 alpha T + 2 (alpha T)^3 / 3 - 2 (alpha T)^2 - 4 alpha T e) / (2 alpha^5)
//       q12 = (e^2 + 1 - 2 e + 2 alpha T e - 2 alpha T + (alpha T)^2) / (2 alpha^4)
//       q13 = (1 - e^2 - 2 alpha T e) / (2 alpha^3)
//       q22 = (4 e - 3 - e^2 + 2 alpha T) / (2 alpha^3)
//       q23 = (e^2 + 1 - 2 e) / (2 alpha^2)
//       q33 = (1 - e^2) / (2 alpha)
// (tests/models check Q1 against the integral of the continuous model, Van Loan's method).
// tau -> infinity tends to constant acceleration, tau -> 0 to constant velocity.
// For alpha T < 0.5 the closed forms lose digits to cancellation (all of them as alpha -> 0);
// Q1 then comes from integrating the transition's power series term by term (singer.cc).
#pragma once

#include "engine/models/motion_model.h"

namespace localizer::engine {

class SingerModel final : public MotionModel {
 public:
  SingerModel(double tau_s, double accel_std_mps2) : alpha_(1.0 / tau_s), sigma_m_(accel_std_mps2) {}
  const char* name() const override { return "singer"; }
  int state_dim() const override { return 9; }
  Eigen::VectorXd Propagate(const Eigen::VectorXd& x, double dt_s) const override;
  Eigen::MatrixXd Jacobian(const Eigen::VectorXd& x, double dt_s) const override;
  Eigen::MatrixXd ProcessNoise(const Eigen::VectorXd& x, double dt_s) const override;

  Eigen::Matrix3d AxisTransition(double dt_s) const;
  Eigen::Matrix3d AxisNoise(double dt_s) const;

 private:
  double alpha_;
  double sigma_m_;
};

}  // namespace localizer::engine
