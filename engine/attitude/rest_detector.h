// Detects that the platform is still, from the bias-corrected gyro and the accelerometer.
//
// A sample is quiet when |omega - bias| < gyro_rps, ||f| - g| < accel_mps2 and
// |f - f_lowpass| < accel_mps2, with f_lowpass a first-order low-pass of the accelerometer
// (time constant 0.2 s; it tells a platform that is still from one turning slowly at a
// constant rate under the gyro threshold only through the gyro, so keep gyro_rps small).
// The platform is at rest once the quiet samples have lasted min_s without a break.
#pragma once

#include <Eigen/Core>
#include <cmath>

namespace localizer::engine {

class RestDetector {
 public:
  RestDetector(double gyro_rps, double accel_mps2, double min_s, double gravity_mps2)
      : gyro_rps_(gyro_rps), accel_mps2_(accel_mps2), min_s_(min_s), gravity_mps2_(gravity_mps2) {}

  // Returns whether the platform is at rest after this sample; dt_s since the previous one.
  bool Update(const Eigen::Vector3d& corrected_rate_rps, const Eigen::Vector3d& accel_mps2, double dt_s) {
    if (!primed_) {
      lowpass_mps2_ = accel_mps2;
      primed_ = true;
    }
    lowpass_mps2_ += (dt_s / (kLowpassTau_s + dt_s)) * (accel_mps2 - lowpass_mps2_);
    const bool quiet = corrected_rate_rps.squaredNorm() < gyro_rps_ * gyro_rps_ &&
                       std::abs(accel_mps2.norm() - gravity_mps2_) < accel_mps2_ &&
                       (accel_mps2 - lowpass_mps2_).squaredNorm() < accel_mps2_ * accel_mps2_;
    quiet_s_ = quiet ? quiet_s_ + dt_s : 0.0;
    return min_s_ > 0.0 && quiet_s_ >= min_s_;
  }

 private:
  static constexpr double kLowpassTau_s = 0.2;
  double gyro_rps_;
  double accel_mps2_;
  double min_s_;
  double gravity_mps2_;
  Eigen::Vector3d lowpass_mps2_ = Eigen::Vector3d::Zero();
  double quiet_s_ = 0.0;
  bool primed_ = false;
};

}  // namespace localizer::engine
