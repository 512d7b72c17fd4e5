// Constant-velocity motion with piecewise-constant white acceleration
// (Bar-Shalom, Li & Kirubarajan, "Estimation with Applications to Tracking", 6.3.3).
//
// State (x, y, z, vx, vy, vz). Over a step dt with acceleration a ~ N(0, q I3) held
// constant during the step, q = accel_noise_mps2^2:
//     x' = F x + G a,   F = [I  dt I; 0  I],   G = [dt^2/2 I; dt I]
//     Q  = q G G^T   = q [dt^4/4 I  dt^3/2 I; dt^3/2 I  dt^2 I]
// The particle filter samples a directly (three normals per particle and step); Kalman
// filters use F and Q.
#pragma once

#include "engine/core/status.h"
#include "engine/core/types.h"
#include "engine/models/motion_model.h"

namespace localizer::engine {

struct ConstantVelocity {
  double accel_noise_mps2 = 0.5;  // std of each acceleration component, >= 0

  Mat6 Transition(double dt_s) const;
  Mat6 ProcessNoise(double dt_s) const;
  Status Validate() const;
};

// The same model behind the MotionModel interface (state (p, v), 6 entries).
class ConstantVelocityModel final : public MotionModel {
 public:
  explicit ConstantVelocityModel(double accel_noise_mps2) : cv_{accel_noise_mps2} {}
  const char* name() const override { return "cv"; }
  int state_dim() const override { return 6; }
  Eigen::VectorXd Propagate(const Eigen::VectorXd& x, double dt_s) const override { return cv_.Transition(dt_s) * x; }
  Eigen::MatrixXd Jacobian(const Eigen::VectorXd&, double dt_s) const override { return cv_.Transition(dt_s); }
  Eigen::MatrixXd ProcessNoise(const Eigen::VectorXd&, double dt_s) const override { return cv_.ProcessNoise(dt_s); }

 private:
  ConstantVelocity cv_;
};

}  // namespace localizer::engine
