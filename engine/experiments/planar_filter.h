// The tracker role of the 2-D experiment: a filter over the bicycle state (x, y, heading)
// driven by known controls and updated by noisy position fixes z = (x, y) + n.
//
// Implementations (each header carries its equations):
//   PlanarKalmanFilter    planar_kalman.h     EKF or UKF predictor, Gaussian, Huber or
//                                             Student-t updater
//   PlanarParticleFilter  planar_particle.h   bootstrap particle filter, mixture or
//                                             Gaussian likelihood
// All share the process model: the commanded control plus white Gaussian errors,
//     v = v_cmd + w_v,          w_v ~ N(0, speed_sigma^2)
//     delta = delta_cmd + w_d,  w_d ~ N(0, steering_sigma^2)
// through BicycleModel::Step, the same errors that move the simulated truth (a matched
// model: the experiment isolates the measurement-noise assumption).
#pragma once

#include <Eigen/Core>
#include <string>

#include "engine/core/status.h"
#include "engine/experiments/bicycle_model.h"

namespace localizer::engine::experiments {

struct ControlNoise {
  double speed_sigma_mps = 0.1;      // per step; ~3 % of 3.5 m/s
  double steering_sigma_rad = 0.02;  // per step; 1.15 deg

  Status Validate() const;  // INVALID_ARGUMENT naming the field unless >= 0 and finite
};

struct PlanarBelief {
  PlanarState mean = PlanarState::Zero();
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
};

class PlanarFilter {
 public:
  virtual ~PlanarFilter() = default;

  // Restart from a Gaussian belief (covariance symmetric positive semi-definite).
  virtual void Initialise(const PlanarBelief& belief) = 0;
  // Propagate by one step of dt_s under the commanded control.
  virtual void Predict(const BicycleControl& command, double dt_s) = 0;
  // Condition on one position fix, metres.
  virtual void Update(const Eigen::Vector2d& z_m) = 0;
  // The point estimate (posterior mean) after the last call.
  virtual PlanarState Estimate() const = 0;
};

}  // namespace localizer::engine::experiments
