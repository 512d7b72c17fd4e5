#include "engine/experiments/closed_course.h"

#include <cmath>
#include <numbers>
#include <string>

#include "engine/sim/invalid_value.h"

namespace localizer::engine::experiments {
namespace {

constexpr double kQuarterTurnRad = 0.5 * std::numbers::pi;
constexpr double kMaxSteeringRad = 1.2;
constexpr double kMaxSteps = 1e6;

bool PositiveFinite(double value) { return value > 0.0 && std::isfinite(value); }

Status Invalid(const std::string& field, double value, const std::string& requirement) {
  return sim_detail::Invalid(field, value, requirement);
}

int StraightSteps(const CourseOptions& o) {
  return static_cast<int>(std::lround(o.straight_m / (o.speed_mps * o.dt_s)));
}

int TurnSteps(const CourseOptions& o) {
  const long steps = std::lround(kQuarterTurnRad * o.turn_radius_m / (o.speed_mps * o.dt_s));
  return static_cast<int>(steps < 1 ? 1 : steps);
}

double CornerSteering(const CourseOptions& o, const BicycleModel& model) {
  const double heading_step_rad = kQuarterTurnRad / TurnSteps(o);
  return std::atan(model.wheelbase_m * heading_step_rad / (o.speed_mps * o.dt_s));
}

}  // namespace

Status CourseOptions::Validate(const BicycleModel& model) const {
  LOCALIZER_RETURN_IF_ERROR(model.Validate());
  if (!PositiveFinite(speed_mps)) return Invalid("speed_mps", speed_mps, "must be positive");
  if (!PositiveFinite(dt_s)) return Invalid("dt_s", dt_s, "must be positive");
  if (!(straight_m >= 0.0 && std::isfinite(straight_m))) {
    return Invalid("straight_m", straight_m, "must be >= 0 and finite");
  }
  if (!PositiveFinite(turn_radius_m)) {
    return Invalid("turn_radius_m", turn_radius_m, "must be positive");
  }
  if (laps < 1) return Invalid("laps", laps, "must be >= 1");
  const double steps = static_cast<double>(laps) * 4.0 *
                       (straight_m / (speed_mps * dt_s) + 2.0 * turn_radius_m / (speed_mps * dt_s) + 1.0);
  if (steps > kMaxSteps) return Invalid("laps", laps, "the course would exceed 10^6 steps");
  if (CornerSteering(*this, model) > kMaxSteeringRad) {
    return Invalid("turn_radius_m", turn_radius_m, "too tight for the wheelbase (corner steering above 1.2 rad)");
  }
  return Status::Ok();
}

StatusOr<CourseSchedule> RoundedRectangleCourse(const CourseOptions& options, const BicycleModel& model) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate(model));
  CourseSchedule course;
  course.straight_steps = StraightSteps(options);
  course.turn_steps = TurnSteps(options);
  course.steering_rad = CornerSteering(options, model);
  course.steps_per_lap = 4 * (course.straight_steps + course.turn_steps);
  course.controls.reserve(static_cast<size_t>(options.laps) * course.steps_per_lap);
  for (int side = 0; side < 4 * options.laps; ++side) {
    for (int k = 0; k < course.straight_steps; ++k) {
      course.controls.push_back({options.speed_mps, 0.0});
    }
    for (int k = 0; k < course.turn_steps; ++k) {
      course.controls.push_back({options.speed_mps, course.steering_rad});
    }
  }
  return course;
}

}  // namespace localizer::engine::experiments
