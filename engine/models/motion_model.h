// The motion-model role (Stone Soup's TransitionModel): how a state moves over dt and how
// uncertain that is. Every model's state starts with position (x, y, z) in m and velocity
// (vx, vy, vz) in m/s, so any filter can read the first six entries the same way; a model
// appends what it needs:
//   ConstantVelocityModel    6: (p, v)                        constant_velocity.h
//   ConstantAccelerationModel 9: (p, v, a)                    constant_acceleration.h
//   CoordinatedTurnModel     7: (p, v, omega)                 coordinated_turn.h
//   SingerModel              9: (p, v, a)                     singer.h
// Kalman-type filters use Propagate, Jacobian and ProcessNoise; particle filters sample
// x' = Propagate(x) + w, w ~ N(0, ProcessNoise(x)).
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>

#include "engine/core/status.h"

namespace localizer::engine {

class MotionModel {
 public:
  virtual ~MotionModel() = default;

  virtual const char* name() const = 0;  // "cv", "ca", "ct", "singer"
  virtual int state_dim() const = 0;
  // x' = f(x, dt), the noise-free propagation (x has state_dim() entries, dt_s >= 0).
  virtual Eigen::VectorXd Propagate(const Eigen::VectorXd& x, double dt_s) const = 0;
  // df/dx at x: the transition matrix F for linear models.
  virtual Eigen::MatrixXd Jacobian(const Eigen::VectorXd& x, double dt_s) const = 0;
  // Covariance of the noise the step adds (symmetric positive semi-definite).
  virtual Eigen::MatrixXd ProcessNoise(const Eigen::VectorXd& x, double dt_s) const = 0;
  // A state at position p with velocity v and the model's extra entries zero.
  Eigen::VectorXd FromPositionVelocity(const Eigen::Vector3d& p, const Eigen::Vector3d& v) const {
    Eigen::VectorXd x = Eigen::VectorXd::Zero(state_dim());
    x.head<3>() = p;
    x.segment<3>(3) = v;
    return x;
  }
};

// Which model MakeMotionModel builds. Names on the wire and in flags: cv, ca, ct, singer
// (each model's name()).
enum class MotionModelKind { kCv, kCa, kCt, kSinger };

// INVALID_ARGUMENT "<field> 'x' is not one of: cv, ca, ct, singer".
StatusOr<MotionModelKind> ParseMotionModelKind(const std::string& name, const std::string& field);
const char* MotionModelKindName(MotionModelKind kind);

// Options for MakeMotionModel; each model reads the fields its header names.
struct MotionModelOptions {
  double accel_noise_mps2 = 1.0;         // cv: std of the piecewise-constant white acceleration
                                         // ct: the same, per axis
  double jerk_psd = 1.0;                 // ca: power spectral density of the white jerk, m^2/s^5
  double turn_rate_noise_radps2 = 0.05;  // ct: std of the turn rate's random walk, rad/s per sqrt(s)
  double singer_tau_s = 5.0;             // singer: manoeuvre time constant
  double singer_accel_std_mps2 = 2.0;    // singer: std of the manoeuvre acceleration
};

// The model `kind` names with `options`' noise; INVALID_ARGUMENT for invalid options.
StatusOr<std::unique_ptr<MotionModel>> MakeMotionModel(MotionModelKind kind, const MotionModelOptions& options);

}  // namespace localizer::engine
