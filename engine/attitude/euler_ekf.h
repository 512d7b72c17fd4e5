// The seed's attitude EKF: state x = (roll, pitch, yaw) in rad, covariance P (3x3).
// Kept beside the quaternion filter for comparison; it has no bias states and is singular
// at pitch = +-90 degrees (tan and 1/cos of pitch below), where the quaternion filter is not.
//
// Propagation ("seed eq. 2", explicit Euler integration over dt = t_k - t_{k-1}):
//     x <- x + E(roll, pitch) omega_m dt,   E = EulerRateMatrix (attitude_math.h),
//     F = I + dt d(E omega)/dx,  with the non-zero partial derivatives
//       d roll_dot/d roll  = (cos r q - sin r s) tan p,   d roll_dot/d pitch = (sin r q + cos r s) / cos^2 p,
//       d pitch_dot/d roll = -sin r q - cos r s,
//       d yaw_dot/d roll   = (cos r q - sin r s) / cos p, d yaw_dot/d pitch  = (sin r q + cos r s) tan p / cos p,
//     (omega_m = (p_rate, q, s) body rates), P <- F P F^T + E (sigma_g^2 dt I) E^T.
// Accelerometer update ("seed eq. 3"), when ||f| - g| <= accel_reject_mps2:
//     z = (atan2(f_y, f_z), atan2(-f_x, sqrt(f_y^2 + f_z^2))),  H = [I2 0],
//     R_meas = sigma_a^2 I2 with sigma_a as in the quaternion filter (inflated by ||f| - g|),
//     the roll innovation wrapped into (-pi, pi].
// Magnetometer update (use_mag, same reference and disturbance test as the quaternion filter):
//     the field levelled by the estimated roll and pitch, m_l = Ry(pitch) Rx(roll) m_body,
//     z = atan2(m_l,east, m_l,north) - mag_declination_rad (the yaw that puts the field at the
//     declination), H = [0 0 1], R_meas = mag_heading_sd_rad^2, innovation wrapped.
// The gyro bias is not estimated (the seed's 3-state filter), so it shows as a slow heading
// drift without the magnetometer and a small tilt offset. Yaw and roll are kept in (-pi, pi].
// Cost per update: a few 3x3 products and the trigonometry (about 0.2 µs of CPU, 0.3 µs with
// the magnetometer; tests/bench/attitude_bench.cc); fixed-size, no heap.
#pragma once

#include <Eigen/Core>

#include "engine/attitude/attitude_filter.h"
#include "engine/attitude/mag_reference.h"

namespace localizer::engine {

class EulerEkf final : public AttitudeFilter {
 public:
  // `options` must be valid (AttitudeFilterOptions::Validate; CreateAttitudeFilter checks).
  explicit EulerEkf(const AttitudeFilterOptions& options);
  EulerEkf(const EulerEkf&) = delete;
  EulerEkf& operator=(const EulerEkf&) = delete;

  Status Update(const ImuSample& sample) override;
  AttitudeEstimate estimate() const override;
  AttitudeFilterKind kind() const override { return AttitudeFilterKind::kEuler; }

  const Eigen::Matrix3d& covariance() const { return p_; }

 private:
  void Initialise(const ImuSample& sample);
  bool AccelUpdate(const Eigen::Vector3d& accel_mps2);
  bool MagUpdate(const Eigen::Vector3d& mag_uT, double t_s);

  AttitudeFilterOptions options_;
  MagReference mag_reference_;
  Eigen::Vector3d x_ = Eigen::Vector3d::Zero();  // roll, pitch, yaw
  Eigen::Matrix3d p_ = Eigen::Matrix3d::Zero();
  double t_s_ = 0.0;
  bool initialised_ = false;
  bool accel_used_ = false;
  bool mag_used_ = false;
};

}  // namespace localizer::engine
