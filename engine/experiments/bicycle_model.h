// The kinematic bicycle model of a car-like vehicle in the plane, as a discrete-time
// transition with known controls (Stone Soup's TransitionModel role for the 2-D experiment).
//
// State s = (x, y, theta): rear-axle position in m and heading in rad (counter-clockwise
// from +x; never wrapped, so a lap adds 2 pi). Control u = (v, delta): speed in m/s and
// front-wheel steering angle in rad, held over the step. With wheelbase L and step dt,
// one explicit-Euler step is
//     x'     = x + v dt cos(theta)
//     y'     = y + v dt sin(theta)
//     theta' = theta + v dt tan(delta) / L
// Its Jacobians, for the EKF:
//     F = ds'/ds = [[1, 0, -v dt sin(theta)],      G = ds'/du = [[dt cos(theta), 0],
//                   [0, 1,  v dt cos(theta)],                    [dt sin(theta), 0],
//                   [0, 0,  1              ]]                    [dt tan(delta) / L,
//                                                                  v dt / (L cos^2(delta))]]
// Euler rather than the exact arc: the truth and every filter use the same map, so the
// experiment compares filters, not integrators; closed courses are built for this map
// (closed_course.h). Pure functions, no state, thread-safe; a few trig calls per step.
#pragma once

#include <Eigen/Core>

#include "engine/core/status.h"

namespace localizer::engine::experiments {

using PlanarState = Eigen::Vector3d;  // (x_m, y_m, heading_rad)
enum PlanarIndex { kPx = 0, kPy = 1, kHeading = 2 };

struct BicycleControl {
  double speed_mps = 0.0;
  double steering_rad = 0.0;  // |steering| < pi / 2
};

struct BicycleModel {
  double wheelbase_m = 2.5;  // L: a mid-size car (the seed states one but not its value)

  Status Validate() const;  // INVALID_ARGUMENT naming wheelbase_m unless positive and finite

  PlanarState Step(const PlanarState& s, const BicycleControl& u, double dt_s) const;
  Eigen::Matrix3d StateJacobian(const PlanarState& s, const BicycleControl& u, double dt_s) const;
  Eigen::Matrix<double, 3, 2> ControlJacobian(const PlanarState& s, const BicycleControl& u, double dt_s) const;
  // Heading change of one step: v dt tan(delta) / L.
  double HeadingStep(const BicycleControl& u, double dt_s) const;
};

}  // namespace localizer::engine::experiments
