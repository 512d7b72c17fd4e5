#include "engine/attitude/attitude_math.h"

#include <algorithm>

namespace localizer::engine {

Eigen::Quaterniond QuaternionFromEuler(const Eigen::Vector3d& roll_pitch_yaw_rad) {
  const Eigen::Quaterniond q = Eigen::AngleAxisd(roll_pitch_yaw_rad.z(), Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(roll_pitch_yaw_rad.y(), Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(roll_pitch_yaw_rad.x(), Eigen::Vector3d::UnitX());
  return q.normalized();
}

Eigen::Vector3d EulerFromQuaternion(const Eigen::Quaterniond& q) {
  // Entries of R = Rz Ry Rx written out from the quaternion, so no full matrix is formed.
  const double w = q.w(), x = q.x(), y = q.y(), z = q.z();
  const double r20 = 2.0 * (x * z - w * y);
  const double r21 = 2.0 * (y * z + w * x);
  const double r22 = 1.0 - 2.0 * (x * x + y * y);
  const double r10 = 2.0 * (x * y + w * z);
  const double r00 = 1.0 - 2.0 * (y * y + z * z);
  const double pitch = std::asin(std::clamp(-r20, -1.0, 1.0));
  if (std::abs(r20) > 1.0 - 1e-12) {  // gimbal lock: put the whole rotation about Up in yaw
    const double r01 = 2.0 * (x * y - w * z);
    const double r11 = 1.0 - 2.0 * (x * x + z * z);
    return {0.0, pitch, std::atan2(-r01, r11)};
  }
  return {std::atan2(r21, r22), pitch, std::atan2(r10, r00)};
}

Eigen::Matrix3d EulerRateMatrix(double roll_rad, double pitch_rad) {
  const double sr = std::sin(roll_rad), cr = std::cos(roll_rad);
  const double cp = std::cos(pitch_rad), tp = std::tan(pitch_rad);
  Eigen::Matrix3d e;
  e << 1.0, sr * tp, cr * tp,  //
      0.0, cr, -sr,            //
      0.0, sr / cp, cr / cp;
  return e;
}

Eigen::Vector2d TiltFromAccelerometer(const Eigen::Vector3d& accel_mps2) {
  const double roll = std::atan2(accel_mps2.y(), accel_mps2.z());
  const double pitch = std::atan2(-accel_mps2.x(), std::hypot(accel_mps2.y(), accel_mps2.z()));
  return {roll, pitch};
}

}  // namespace localizer::engine
