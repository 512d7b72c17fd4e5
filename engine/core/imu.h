// One inertial-measurement-unit sample, as an attitude filter consumes it.
//
// Conventions (every attitude-related header follows them):
//  - body frame: the IMU's own axes, right-handed, fixed to the platform (and so to the
//    array's body-frame sensor positions);
//  - world frame: East-North-Up (x = East, y = North, z = Up), the frame the engine tracks in;
//  - units: gyro rad/s, accelerometer m/s^2 (specific force: at rest it reads +g along the
//    body's up axis, about +9.81 on z when level), magnetometer µT.
#pragma once

#include <Eigen/Core>
#include <limits>

namespace localizer::engine {

struct ImuSample {
  double t_s = 0.0;  // on the same clock as the blocks
  Eigen::Vector3d gyro_rps = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_mps2 = Eigen::Vector3d::Zero();
  // NaN components when the IMU has no magnetometer (or the sample carries none).
  Eigen::Vector3d mag_uT = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
};

}  // namespace localizer::engine
