// Coordinated turn in the horizontal plane with unknown turn rate (Bar-Shalom, Li &
// Kirubarajan 11.7; Li & Jilkov 2003, eq. 64-66), 3-D: the source turns at omega (rad/s,
// positive counter-clockwise seen from +z) in x-y at constant speed while z moves at
// constant velocity. State (x, y, z, vx, vy, vz, omega), 7 entries. Over T, with
// s = sin(omega T), c = cos(omega T):
//     x'  = x + (s vx - (1 - c) vy) / omega        vx' = c vx - s vy
//     y'  = y + ((1 - c) vx + s vy) / omega        vy' = s vx + c vy
//     z'  = z + vz T,  vz' = vz,  omega' = omega
// For |omega T| < 1e-2 the coefficients come from their Taylor series (the closed forms
// lose digits to cancellation there), so omega = 0 is constant velocity exactly. Jacobian: analytic, including the
// omega column. Process noise: white acceleration per axis as constant_velocity.h
// (accel_noise_mps2, in the world frame) plus a random walk of omega with std
// turn_rate_noise * sqrt(T).
#pragma once

#include "engine/models/motion_model.h"

namespace localizer::engine {

class CoordinatedTurnModel final : public MotionModel {
 public:
  CoordinatedTurnModel(double accel_noise_mps2, double turn_rate_noise)
      : accel_noise_(accel_noise_mps2), turn_noise_(turn_rate_noise) {}
  const char* name() const override { return "ct"; }
  int state_dim() const override { return 7; }
  Eigen::VectorXd Propagate(const Eigen::VectorXd& x, double dt_s) const override;
  Eigen::MatrixXd Jacobian(const Eigen::VectorXd& x, double dt_s) const override;
  Eigen::MatrixXd ProcessNoise(const Eigen::VectorXd& x, double dt_s) const override;

 private:
  double accel_noise_;
  double turn_noise_;
};

}  // namespace localizer::engine
