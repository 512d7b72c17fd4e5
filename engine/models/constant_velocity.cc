#include "engine/models/constant_velocity.h"

#include <cmath>
#include <string>

namespace localizer::engine {

Mat6 ConstantVelocity::Transition(double dt_s) const {
  Mat6 f = Mat6::Identity();
  f.topRightCorner<3, 3>() = dt_s * Mat3::Identity();
  return f;
}

Mat6 ConstantVelocity::ProcessNoise(double dt_s) const {
  const double q = accel_noise_mps2 * accel_noise_mps2;
  Mat6 noise = Mat6::Zero();
  noise.topLeftCorner<3, 3>() = q * std::pow(dt_s, 4) / 4.0 * Mat3::Identity();
  noise.topRightCorner<3, 3>() = q * std::pow(dt_s, 3) / 2.0 * Mat3::Identity();
  noise.bottomLeftCorner<3, 3>() = noise.topRightCorner<3, 3>();
  noise.bottomRightCorner<3, 3>() = q * dt_s * dt_s * Mat3::Identity();
  return noise;
}

Status ConstantVelocity::Validate() const {
  if (!(accel_noise_mps2 >= 0.0) || !std::isfinite(accel_noise_mps2)) {
    return InvalidArgument("accel_noise_mps2 must be finite and >= 0, got " + std::to_string(accel_noise_mps2));
  }
  return Status::Ok();
}

}  // namespace localizer::engine
