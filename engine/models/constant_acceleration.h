// Constant acceleration driven by white jerk (Bar-Shalom, Li & Kirubarajan 6.2.3, the
// continuous Wiener-process acceleration model). State (p, v, a), 9 entries. Per axis, with
// jerk power spectral density q (m^2/s^5) and step T:
//     F1 = [1 T T^2/2; 0 1 T; 0 0 1]
//     Q1 = q [T^5/20 T^4/8 T^3/6; T^4/8 T^3/3 T^2/2; T^3/6 T^2/2 T]
// and the three axes are independent (F = F1 (x) I3, Q = Q1 (x) I3 in the (p, v, a) order).
#pragma once

#include "engine/models/motion_model.h"

namespace localizer::engine {

class ConstantAccelerationModel final : public MotionModel {
 public:
  explicit ConstantAccelerationModel(double jerk_psd) : q_(jerk_psd) {}
  const char* name() const override { return "ca"; }
  int state_dim() const override { return 9; }
  Eigen::VectorXd Propagate(const Eigen::VectorXd& x, double dt_s) const override;
  Eigen::MatrixXd Jacobian(const Eigen::VectorXd& x, double dt_s) const override;
  Eigen::MatrixXd ProcessNoise(const Eigen::VectorXd& x, double dt_s) const override;

 private:
  double q_;
};

// The 9x9 matrix with the 3x3 per-axis block `axis` for every axis, in (p, v, a) order:
// entry (3 i + k, 3 j + k) = axis(i, j). Shared by the models with per-axis kinematics.
Eigen::MatrixXd KronAxes(const Eigen::Matrix3d& axis);

}  // namespace localizer::engine
