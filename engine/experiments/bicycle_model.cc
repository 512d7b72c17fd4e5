#include "engine/experiments/bicycle_model.h"

#include <cmath>
#include <string>

#include "engine/sim/invalid_value.h"

namespace localizer::engine::experiments {

Status BicycleModel::Validate() const {
  if (!(wheelbase_m > 0.0 && std::isfinite(wheelbase_m))) {
    return sim_detail::Invalid("wheelbase_m", wheelbase_m, "must be positive and finite");
  }
  return Status::Ok();
}

double BicycleModel::HeadingStep(const BicycleControl& u, double dt_s) const {
  return u.speed_mps * dt_s * std::tan(u.steering_rad) / wheelbase_m;
}

PlanarState BicycleModel::Step(const PlanarState& s, const BicycleControl& u, double dt_s) const {
  const double travel_m = u.speed_mps * dt_s;
  return {s[kPx] + travel_m * std::cos(s[kHeading]), s[kPy] + travel_m * std::sin(s[kHeading]),
          s[kHeading] + HeadingStep(u, dt_s)};
}

Eigen::Matrix3d BicycleModel::StateJacobian(const PlanarState& s, const BicycleControl& u, double dt_s) const {
  const double travel_m = u.speed_mps * dt_s;
  Eigen::Matrix3d f = Eigen::Matrix3d::Identity();
  f(kPx, kHeading) = -travel_m * std::sin(s[kHeading]);
  f(kPy, kHeading) = travel_m * std::cos(s[kHeading]);
  return f;
}

Eigen::Matrix<double, 3, 2> BicycleModel::ControlJacobian(const PlanarState& s, const BicycleControl& u,
                                                          double dt_s) const {
  const double cos_delta = std::cos(u.steering_rad);
  Eigen::Matrix<double, 3, 2> g;
  g << dt_s * std::cos(s[kHeading]), 0.0,  //
      dt_s * std::sin(s[kHeading]), 0.0,   //
      dt_s * std::tan(u.steering_rad) / wheelbase_m, u.speed_mps * dt_s / (wheelbase_m * cos_delta * cos_delta);
  return g;
}

}  // namespace localizer::engine::experiments
