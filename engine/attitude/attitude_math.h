// Rotation helpers shared by the attitude filters, the scoring and the simulator.
//
// Conventions (engine/core/imu.h): body frame = the IMU's axes; world frame = East-North-Up;
// a quaternion q is the body -> world rotation, v_world = q * v_body * q^-1, and is written
// (w, x, y, z) in files and messages. Eigen::Quaterniond's constructor takes (w, x, y, z) but
// coeffs() stores (x, y, z, w): never index coeffs() by position, use .w() .x() .y() .z().
// Euler angles are the intrinsic z-y'-x'' (yaw, pitch, roll) sequence:
//     R_body_to_world = Rz(yaw) Ry(pitch) Rx(roll),
// roll about body x, pitch about y, yaw about world Up (counter-clockwise seen from above,
// so yaw = 0 has the body x axis pointing East). Pitch lies in [-pi/2, pi/2]; at +-pi/2 roll
// and yaw are not separately defined (gimbal lock) and EulerFromQuaternion returns roll = 0.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

namespace localizer::engine {

// Wraps an angle into (-pi, pi].
inline double WrapAngle(double angle_rad) {
  // Inside (-pi, pi) remainder returns the angle itself: skip its libm call (most calls).
  if (std::abs(angle_rad) < M_PI) return angle_rad;
  angle_rad = std::remainder(angle_rad, 2.0 * M_PI);
  return angle_rad <= -M_PI ? angle_rad + 2.0 * M_PI : angle_rad;
}

// [v x]: Skew(v) * u == v.cross(u).
inline Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return s;
}

// exp(theta / 2) as a unit quaternion: rotation by |theta| about theta / |theta|. Exact for
// any angle: below 0.1 rad (every gyro step and filter correction in practice) by the Taylor
// series of cos(x/2) and sin(x/2)/x to x^6, whose remainder is below 1e-15 there, so the
// per-update path needs no sqrt, sin or cos.
inline Eigen::Quaterniond QuaternionFromRotationVector(const Eigen::Vector3d& theta_rad) {
  const double x2 = theta_rad.squaredNorm();
  if (x2 < 0.01) {
    const double c = 1.0 - x2 * (1.0 / 8.0 - x2 * (1.0 / 384.0 - x2 * (1.0 / 46080.0)));
    const double s = 0.5 - x2 * (1.0 / 48.0 - x2 * (1.0 / 3840.0 - x2 * (1.0 / 645120.0)));
    return Eigen::Quaterniond(c, s * theta_rad.x(), s * theta_rad.y(), s * theta_rad.z());
  }
  const double angle = std::sqrt(x2);
  const double s = std::sin(0.5 * angle) / angle;
  return Eigen::Quaterniond(std::cos(0.5 * angle), s * theta_rad.x(), s * theta_rad.y(), s * theta_rad.z());
}

// Rz(yaw) Ry(pitch) Rx(roll) as a quaternion.
Eigen::Quaterniond QuaternionFromEuler(const Eigen::Vector3d& roll_pitch_yaw_rad);
// (roll, pitch, yaw) of q (see the convention above); yaw and roll in (-pi, pi].
Eigen::Vector3d EulerFromQuaternion(const Eigen::Quaterniond& q);

// The Euler-rate map: d(roll, pitch, yaw)/dt = EulerRateMatrix(roll, pitch) * omega_body,
//     [1  sin(r) tan(p)   cos(r) tan(p)]
//     [0  cos(r)          -sin(r)      ]
//     [0  sin(r)/cos(p)   cos(r)/cos(p)]
// singular at pitch = +-pi/2. The same matrix maps a small body-frame rotation error to the
// Euler-angle error it causes, which is how the filters report Euler standard deviations.
Eigen::Matrix3d EulerRateMatrix(double roll_rad, double pitch_rad);

// Roll and pitch of a body whose accelerometer reads the specific force f (at rest,
// f = R^T (0, 0, g): +g on the body's up axis), the seed's eq. 3 for a z-up world:
//     roll = atan2(f_y, f_z),  pitch = atan2(-f_x, sqrt(f_y^2 + f_z^2)).
Eigen::Vector2d TiltFromAccelerometer(const Eigen::Vector3d& accel_mps2);

// The angle of a world-frame horizontal vector east of North: atan2(v_east, v_north).
inline double AzimuthEastOfNorth(const Eigen::Vector3d& v_world) { return std::atan2(v_world.x(), v_world.y()); }

}  // namespace localizer::engine
