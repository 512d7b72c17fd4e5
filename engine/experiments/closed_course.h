// The closed course of the 2-D experiment: a rounded rectangle (a square with quarter-circle
// corners), driven counter-clockwise from the origin heading +x, the given number of laps.
//
// The seed says only "a closed course, driven twice". One lap is four identical sides, each
//     n_s = round(straight_m / (v dt)) steps straight (delta = 0), then
//     n_t = round((pi / 2) turn_radius_m / (v dt)) steps turning left with
//     delta = atan(L (pi / 2) / (n_t v dt)),
// so the bicycle model (bicycle_model.h) turns by exactly pi / 2 per corner. Each side's
// displacement is the previous one rotated by +90 degrees, and four such vectors sum to
// zero: one lap of the Euler map ends at the start, heading + 2 pi, up to rounding
// (< 1e-9 m for the defaults), whatever n_s and n_t are. The defaults: 60 straight steps
// (21 m) and 30 turning steps (corner radius 6.68 m, steering 0.357 rad = 20.5 deg with a
// 2.5 m wheelbase) per side, so a lap is 360 steps = 36 s = 126 m, a 34.4 m square.
#pragma once

#include <vector>

#include "engine/core/status.h"
#include "engine/experiments/bicycle_model.h"

namespace localizer::engine::experiments {

struct CourseOptions {
  double speed_mps = 3.5;       // constant commanded speed (seed: 3.5 m/s)
  double dt_s = 0.1;            // control and measurement step (seed: 0.1 s)
  double straight_m = 21.0;     // length of each straight side
  double turn_radius_m = 6.68;  // radius of each quarter-circle corner
  int laps = 2;                 // seed: twice

  // INVALID_ARGUMENT naming the field: speed, dt, turn radius not positive and finite,
  // straight negative, laps < 1, more than 10^6 steps, or a steering angle above 1.2 rad.
  Status Validate(const BicycleModel& model) const;
};

struct CourseSchedule {
  std::vector<BicycleControl> controls;  // one per step, laps * steps_per_lap of them
  int steps_per_lap = 0;
  int straight_steps = 0;     // n_s
  int turn_steps = 0;         // n_t
  double steering_rad = 0.0;  // delta in the corners
};

// The commands of `options.laps` laps for `model`; the errors of Validate.
StatusOr<CourseSchedule> RoundedRectangleCourse(const CourseOptions& options, const BicycleModel& model);

}  // namespace localizer::engine::experiments
