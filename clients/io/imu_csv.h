// IMU recordings and orientation estimates as CSV (the BROAD benchmark's columns, see
// ../shared/data/README.md).
//
// imu.csv (one row per sample, t_s strictly increasing):
//   t_s,                                   seconds
//   gyr_x_rps,gyr_y_rps,gyr_z_rps,          gyro, rad/s, body frame
//   acc_x_mps2,acc_y_mps2,acc_z_mps2,       specific force, m/s^2 (+g up at rest)
//   mag_x_uT,mag_y_uT,mag_z_uT,             magnetometer, µT (optional; needed for --mag)
//   truth_qw,truth_qx,truth_qy,truth_qz,    truth body -> ENU quaternion (optional; NaN where
//                                           unknown; needed for scoring)
//   movement                                1 where scored (optional; needed for scoring)
// orientation.csv (one row per IMU sample, written by `localizer-cli attitude`):
//   t_s,qw,qx,qy,qz,                       body -> world (East-North-Up), (w, x, y, z)
//   roll_rad,pitch_rad,yaw_rad,            z-y'-x'' Euler angles of q
//   roll_sd_rad,pitch_sd_rad,yaw_sd_rad    their first-order std (engine/attitude/attitude_filter.h)
// Columns are found by name; extra columns are ignored.
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "engine/attitude/attitude_filter.h"
#include "engine/core/imu.h"
#include "engine/core/status.h"

namespace localizer::io {

struct ImuRecording {
  std::vector<engine::ImuSample> samples;  // mag_uT NaN when the file has no mag columns
  bool has_mag = false;
  // Present only when read with truth: one entry per sample.
  std::vector<Eigen::Quaterniond> truth;
  std::vector<bool> movement;
};

// Reads imu.csv. NOT_FOUND when the file cannot be opened; INVALID_ARGUMENT naming the file,
// line and column for a missing required column (mag when need_mag, truth and movement when
// need_truth), a malformed or non-finite t_s / gyro / accel / mag value, or t_s not
// increasing. Truth may be NaN (markers lost); a truth that is finite must have norm ~1.
StatusOr<ImuRecording> ReadImuCsv(const std::string& path, bool need_mag, bool need_truth);

// Writes orientation.csv; INVALID_ARGUMENT (naming the path) when it cannot be written.
Status WriteOrientationCsv(const std::string& path, const std::vector<engine::AttitudeEstimate>& estimates);

struct OrientationRow {
  double t_s = 0.0;
  Eigen::Quaterniond body_to_world = Eigen::Quaterniond::Identity();
};

// Reads the t_s and quaternion columns of orientation.csv (errors as ReadImuCsv).
StatusOr<std::vector<OrientationRow>> ReadOrientationCsv(const std::string& path);

}  // namespace localizer::io
