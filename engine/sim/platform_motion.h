// A platform's known attitude over time and the IMU readings it would produce: the truth for
// the attitude filters' tests, and the rotation that carries an array's body-frame sensor
// positions into the world (p_world = At(t) * p_body + origin).
//
// Conventions (engine/core/imu.h): body = the IMU's (and the array's) axes, world =
// East-North-Up, quaternions body -> world, Euler angles z-y'-x'' (R = Rz(yaw) Ry(pitch)
// Rx(roll)), gyro rad/s, accelerometer m/s^2 (specific force), magnetometer µT.
//
// The attitude is
//     q(t) = QEuler(e(t)) (x) exp(omega_c t / 2),
//     e(t) = euler0 + euler_rate t + amplitude .* sin(2 pi frequency t + phase)   (per axis),
// i.e. sinusoidal (and/or linearly growing) roll, pitch, yaw, followed by a constant body-rate
// spin omega_c; either part may be zero. Pitch may pass +-90 degrees: e(t) is only a
// parameterisation, q(t) and the body rate stay smooth there. The body rate, exactly:
//     omega(t) = R(exp(omega_c t / 2))^T w_e(t) + omega_c,
//     w_e = (r' - y' sin p,  p' cos r + y' sin r cos p,  -p' sin r + y' cos r cos p)
// (the inverse of the Euler-rate map, defined at every pitch). A world-frame linear
// acceleration a(t) = linear_amplitude_mps2 .* sin(2 pi linear_frequency_hz t) may be added
// (the platform shakes in place; it is not integrated into a position).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "engine/core/imu.h"

namespace localizer::engine {

struct AttitudeTrajectoryOptions {
  Eigen::Vector3d euler0_rad = Eigen::Vector3d::Zero();             // (roll, pitch, yaw) at t = 0
  Eigen::Vector3d euler_rate_rps = Eigen::Vector3d::Zero();         // linear growth of each angle
  Eigen::Vector3d amplitude_rad = Eigen::Vector3d::Zero();          // sinusoid amplitude per angle
  Eigen::Vector3d frequency_hz = Eigen::Vector3d::Zero();           // sinusoid frequency per angle
  Eigen::Vector3d phase_rad = Eigen::Vector3d::Zero();              // sinusoid phase per angle
  Eigen::Vector3d constant_rate_rps = Eigen::Vector3d::Zero();      // omega_c, body frame
  Eigen::Vector3d linear_amplitude_mps2 = Eigen::Vector3d::Zero();  // world frame
  double linear_frequency_hz = 0.0;
};

class AttitudeTrajectory {
 public:
  explicit AttitudeTrajectory(const AttitudeTrajectoryOptions& options) : options_(options) {}
  // Rotation at a constant body rate from `start` (start (x) exp(omega t / 2)).
  static AttitudeTrajectory ConstantRate(const Eigen::Vector3d& start_euler_rad, const Eigen::Vector3d& body_rate_rps);

  Eigen::Quaterniond At(double t_s) const;                    // body -> world, unit
  Eigen::Vector3d BodyRate(double t_s) const;                 // rad/s, body frame
  Eigen::Vector3d LinearAccelerationWorld(double t_s) const;  // m/s^2, world frame
  const AttitudeTrajectoryOptions& options() const { return options_; }

 private:
  AttitudeTrajectoryOptions options_;
};

// Sensor errors of the synthetic IMU. Defaults: a clean sensor at rest on Earth.
struct ImuNoise {
  double gyro_noise_sd_rps = 0.0;                           // white noise std per sample, each axis
  Eigen::Vector3d gyro_bias_rps = Eigen::Vector3d::Zero();  // constant bias
  double accel_noise_sd_mps2 = 0.0;                         // per sample, each axis
  double mag_noise_sd_uT = 0.0;                             // per sample, each axis
  double gravity_mps2 = 9.81;
  // Earth's field in the world frame (about Berlin's: 17 µT North, 46 µT down; dip 70 deg).
  Eigen::Vector3d mag_world_uT = Eigen::Vector3d(0.0, 17.0, -46.0);
  bool with_mag = true;  // false: mag_uT is NaN (an IMU without magnetometer)
  // A magnetic disturbance (a nearby iron object, fixed in the world) added to the field
  // for t in [disturbance_start_s, disturbance_end_s).
  Eigen::Vector3d mag_disturbance_world_uT = Eigen::Vector3d::Zero();
  double disturbance_start_s = 0.0;
  double disturbance_end_s = 0.0;
};

// Samples at t_k = k / rate_hz for k = 0 .. floor(duration_s rate_hz):
//     gyro  = omega(t_k) + bias + n_g,
//     accel = R(t_k)^T (a_lin(t_k) + (0, 0, g)) + n_a,
//     mag   = R(t_k)^T (m_world + disturbance) + n_m.
// Noise from one std::mt19937_64 seeded by `seed` alone (same seed, same samples).
// rate_hz and duration_s must be > 0 (an empty vector otherwise).
std::vector<ImuSample> SynthesiseImu(const AttitudeTrajectory& trajectory, double rate_hz, double duration_s,
                                     const ImuNoise& noise, uint64_t seed);

}  // namespace localizer::engine
