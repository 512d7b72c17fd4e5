#include "engine/attitude/euler_ekf.h"

#include <cmath>
#include <limits>

#include "engine/attitude/attitude_math.h"

namespace localizer::engine {
namespace {

constexpr double kInitialTiltSdRad = 0.1;  // as the quaternion filter's prior
constexpr double kInitialHeadingSdRad = 0.2;

// The field with the estimated roll and pitch removed: Ry(pitch) Rx(roll) m_body.
Eigen::Vector3d LevelledField(const Eigen::Vector3d& mag_uT, double roll, double pitch) {
  const double sr = std::sin(roll), cr = std::cos(roll), sp = std::sin(pitch), cp = std::cos(pitch);
  const double y1 = cr * mag_uT.y() - sr * mag_uT.z();
  const double z1 = sr * mag_uT.y() + cr * mag_uT.z();
  return {cp * mag_uT.x() + sp * z1, y1, -sp * mag_uT.x() + cp * z1};
}

}  // namespace

EulerEkf::EulerEkf(const AttitudeFilterOptions& options)
    : options_(options),
      mag_reference_(options.mag_reference_s, options.mag_norm_tolerance, options.mag_dip_tolerance_rad) {}

void EulerEkf::Initialise(const ImuSample& sample) {
  const Eigen::Vector2d tilt = TiltFromAccelerometer(sample.accel_mps2);
  const bool mag = options_.use_mag && sample.mag_uT.allFinite();
  double yaw = 0.0;
  if (mag) {
    yaw =
        WrapAngle(AzimuthEastOfNorth(LevelledField(sample.mag_uT, tilt.x(), tilt.y())) - options_.mag_declination_rad);
  }
  x_ << tilt.x(), tilt.y(), yaw;
  p_.setZero();
  p_(0, 0) = p_(1, 1) = kInitialTiltSdRad * kInitialTiltSdRad;
  p_(2, 2) = mag ? kInitialHeadingSdRad * kInitialHeadingSdRad : 0.0;
  t_s_ = sample.t_s;
  initialised_ = true;
  accel_used_ = true;
  mag_used_ = mag;
  if (mag) {
    (void)mag_reference_.Observe(QuaternionFromEuler(x_) * sample.mag_uT, sample.t_s);
  }
}

bool EulerEkf::AccelUpdate(const Eigen::Vector3d& accel_mps2) {
  const double norm = accel_mps2.norm();
  const double departure = std::abs(norm - options_.gravity_mps2);
  if (departure > options_.accel_reject_mps2 || norm <= 0.0) return false;
  const double sd = options_.accel_tilt_sd_rad * (1.0 + options_.accel_noise_gain * departure / options_.gravity_mps2);
  const Eigen::Vector2d z = TiltFromAccelerometer(accel_mps2);
  const Eigen::Vector2d nu(WrapAngle(z.x() - x_.x()), z.y() - x_.y());
  // H = [I2 0]: S = P_00..11 + R, K = P.leftCols(2) S^-1.
  Eigen::Matrix2d s = p_.topLeftCorner<2, 2>();
  s.diagonal().array() += sd * sd;
  const Eigen::Matrix<double, 3, 2> pht = p_.leftCols<2>();
  const Eigen::Matrix<double, 3, 2> k = pht * s.inverse();
  x_ += k * nu;
  p_ -= k * pht.transpose();
  p_ = 0.5 * (p_ + p_.transpose()).eval();
  x_.x() = WrapAngle(x_.x());
  x_.z() = WrapAngle(x_.z());
  return true;
}

bool EulerEkf::MagUpdate(const Eigen::Vector3d& mag_uT, double t_s) {
  const Eigen::Vector3d levelled = LevelledField(mag_uT, x_.x(), x_.y());
  const double sy = std::sin(x_.z()), cy = std::cos(x_.z());
  const Eigen::Vector3d field_world(cy * levelled.x() - sy * levelled.y(), sy * levelled.x() + cy * levelled.y(),
                                    levelled.z());
  if (!mag_reference_.Observe(field_world, t_s)) return false;
  if (levelled.head<2>().squaredNorm() < 1e-6) return false;
  const double z = AzimuthEastOfNorth(levelled) - options_.mag_declination_rad;
  const double nu = WrapAngle(z - x_.z());
  const double s = p_(2, 2) + options_.mag_heading_sd_rad * options_.mag_heading_sd_rad;
  const Eigen::Vector3d pht = p_.col(2);
  const Eigen::Vector3d k = pht / s;
  x_ += k * nu;
  p_ -= k * pht.transpose();
  p_ = 0.5 * (p_ + p_.transpose()).eval();
  x_.x() = WrapAngle(x_.x());
  x_.z() = WrapAngle(x_.z());
  return true;
}

Status EulerEkf::Update(const ImuSample& sample) {
  LOCALIZER_RETURN_IF_ERROR(ValidateImuSample(sample, initialised_ ? t_s_ : -std::numeric_limits<double>::infinity()));
  if (!initialised_) {
    Initialise(sample);
    return Status::Ok();
  }
  const double dt_s = sample.t_s - t_s_;
  t_s_ = sample.t_s;
  const double sr = std::sin(x_.x()), cr = std::cos(x_.x());
  const double cp = std::cos(x_.y()), tp = std::tan(x_.y());
  const Eigen::Vector3d& w = sample.gyro_rps;
  Eigen::Matrix3d e;
  e << 1.0, sr * tp, cr * tp, 0.0, cr, -sr, 0.0, sr / cp, cr / cp;
  const double a = cr * w.y() - sr * w.z();  // d(sin r q + cos r s)/d r
  const double b = sr * w.y() + cr * w.z();
  Eigen::Matrix3d f = Eigen::Matrix3d::Identity();
  f(0, 0) += dt_s * a * tp;
  f(0, 1) += dt_s * b / (cp * cp);
  f(1, 0) += dt_s * -b;
  f(2, 0) += dt_s * a / cp;
  f(2, 1) += dt_s * b * tp / cp;
  x_ += (e * w) * dt_s;
  x_.x() = WrapAngle(x_.x());
  x_.z() = WrapAngle(x_.z());
  const double q_gyro = options_.gyro_noise_rps_rthz * options_.gyro_noise_rps_rthz * dt_s;
  p_ = f * p_ * f.transpose() + q_gyro * e * e.transpose();
  accel_used_ = AccelUpdate(sample.accel_mps2);
  mag_used_ = options_.use_mag && sample.mag_uT.allFinite() && MagUpdate(sample.mag_uT, sample.t_s);
  return Status::Ok();
}

AttitudeEstimate EulerEkf::estimate() const {
  AttitudeEstimate e;
  e.t_s = t_s_;
  e.initialised = initialised_;
  e.euler_rad = x_;
  e.body_to_world = QuaternionFromEuler(x_);
  e.sd_rad = p_.diagonal().cwiseMax(0.0).cwiseSqrt();
  // A small Euler error d maps to a body rotation E^-1 d (E^-1 written out: it is regular
  // at every pitch, unlike E), then to the world by R.
  const double sr = std::sin(x_.x()), cr = std::cos(x_.x());
  const double sp = std::sin(x_.y()), cp = std::cos(x_.y());
  Eigen::Matrix3d e_inverse;
  e_inverse << 1.0, 0.0, -sp, 0.0, cr, sr * cp, 0.0, -sr, cr * cp;
  const Eigen::Matrix3d to_world = e.body_to_world.toRotationMatrix() * e_inverse;
  e.world_error_sd_rad = (to_world * p_ * to_world.transpose()).diagonal().cwiseMax(0.0).cwiseSqrt();
  e.accel_used = accel_used_;
  e.mag_used = mag_used_;
  return e;
}

}  // namespace localizer::engine
