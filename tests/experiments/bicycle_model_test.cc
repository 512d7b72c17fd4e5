#include "engine/experiments/bicycle_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "engine/experiments/closed_course.h"

namespace localizer::engine::experiments {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

PlanarState DriveCourse(const BicycleModel& model, const CourseSchedule& course, double dt_s, int steps) {
  PlanarState s = PlanarState::Zero();
  for (int k = 0; k < steps; ++k) s = model.Step(s, course.controls[k], dt_s);
  return s;
}

TEST(ClosedCourse, DefaultLapEndsWhereItStarted) {
  const BicycleModel model;
  const CourseOptions options;
  StatusOr<CourseSchedule> course = RoundedRectangleCourse(options, model);
  ASSERT_TRUE(course.ok()) << course.status().ToString();
  EXPECT_EQ(course->straight_steps, 60);
  EXPECT_EQ(course->turn_steps, 30);
  EXPECT_EQ(course->steps_per_lap, 360);
  ASSERT_EQ(course->controls.size(), 720u);  // two laps
  EXPECT_NEAR(course->steering_rad, 0.357, 1e-3);
  // One lap: back at the origin (tolerance 1e-9 m: rounding only), heading + 2 pi.
  const PlanarState lap = DriveCourse(model, *course, options.dt_s, course->steps_per_lap);
  EXPECT_LT(lap.head<2>().norm(), 1e-9);
  EXPECT_NEAR(lap[kHeading], kTwoPi, 1e-9);
  const PlanarState two = DriveCourse(model, *course, options.dt_s, 2 * course->steps_per_lap);
  EXPECT_LT(two.head<2>().norm(), 1e-9);
  EXPECT_NEAR(two[kHeading], 2.0 * kTwoPi, 1e-9);
}

TEST(ClosedCourse, HalfLapIsOnTheFarSideOfTheSquare) {
  // A course that closes by staying put would pass the test above; this one must travel.
  const BicycleModel model;
  const CourseOptions options;
  StatusOr<CourseSchedule> course = RoundedRectangleCourse(options, model);
  ASSERT_TRUE(course.ok());
  const PlanarState half = DriveCourse(model, *course, options.dt_s, course->steps_per_lap / 2);
  // After two sides (straight +x, corner, straight +y, corner): near (21, 21 + 2 * 6.68) m,
  // the top edge's right end, heading pi. Within half a metre: an Euler corner is not an
  // exact arc (its first step runs straight on, which moves the top edge +0.35 m in x).
  EXPECT_NEAR(half[kPx], 21.0, 0.5);
  EXPECT_NEAR(half[kPy], 34.36, 0.2);
  EXPECT_NEAR(half[kHeading], std::numbers::pi, 1e-9);
}

TEST(ClosedCourse, OtherShapesCloseToo) {
  for (const double straight_m : {0.0, 5.0, 33.0}) {
    for (const double radius_m : {3.0, 10.0}) {
      BicycleModel model;
      model.wheelbase_m = 1.5;
      CourseOptions options;
      options.straight_m = straight_m;
      options.turn_radius_m = radius_m;
      options.laps = 1;
      StatusOr<CourseSchedule> course = RoundedRectangleCourse(options, model);
      ASSERT_TRUE(course.ok()) << course.status().ToString();
      const PlanarState end = DriveCourse(model, *course, options.dt_s, course->steps_per_lap);
      EXPECT_LT(end.head<2>().norm(), 1e-9) << straight_m << " " << radius_m;
    }
  }
}

TEST(ClosedCourse, RejectsBadOptionsNamingTheField) {
  const BicycleModel model;
  CourseOptions options;
  options.laps = 0;
  StatusOr<CourseSchedule> course = RoundedRectangleCourse(options, model);
  ASSERT_FALSE(course.ok());
  EXPECT_EQ(course.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(course.status().message().find("laps"), std::string::npos);
  options = CourseOptions();
  options.turn_radius_m = 0.5;  // steering atan(2.5 / 0.5) > 1.2 rad
  course = RoundedRectangleCourse(options, model);
  ASSERT_FALSE(course.ok());
  EXPECT_NE(course.status().message().find("turn_radius_m"), std::string::npos);
  options = CourseOptions();
  options.speed_mps = -1.0;
  EXPECT_NE(RoundedRectangleCourse(options, model).status().message().find("speed_mps"), std::string::npos);
  BicycleModel bad;
  bad.wheelbase_m = 0.0;
  EXPECT_NE(RoundedRectangleCourse(CourseOptions(), bad).status().message().find("wheelbase_m"), std::string::npos);
}

// Central differences with step h: error O(h^2) ~ 1e-10 for these smooth maps.
TEST(BicycleModel, JacobiansMatchFiniteDifferences) {
  const BicycleModel model{2.7};
  const double dt_s = 0.1;
  const double h = 1e-6;
  for (const PlanarState& s : {PlanarState(1.0, -2.0, 0.3), PlanarState(-5.0, 4.0, 2.9), PlanarState(0.0, 0.0, -1.7)}) {
    for (const BicycleControl& u : {BicycleControl{3.5, 0.0}, BicycleControl{3.5, 0.36}, BicycleControl{1.2, -0.8}}) {
      const Eigen::Matrix3d f = model.StateJacobian(s, u, dt_s);
      for (int j = 0; j < 3; ++j) {
        PlanarState plus = s, minus = s;
        plus[j] += h;
        minus[j] -= h;
        const Eigen::Vector3d column = (model.Step(plus, u, dt_s) - model.Step(minus, u, dt_s)) / (2 * h);
        EXPECT_LT((column - f.col(j)).norm(), 1e-8) << "state column " << j;
      }
      const Eigen::Matrix<double, 3, 2> g = model.ControlJacobian(s, u, dt_s);
      const BicycleControl du[2] = {{h, 0.0}, {0.0, h}};
      for (int j = 0; j < 2; ++j) {
        const BicycleControl plus{u.speed_mps + du[j].speed_mps, u.steering_rad + du[j].steering_rad};
        const BicycleControl minus{u.speed_mps - du[j].speed_mps, u.steering_rad - du[j].steering_rad};
        const Eigen::Vector3d column = (model.Step(s, plus, dt_s) - model.Step(s, minus, dt_s)) / (2 * h);
        EXPECT_LT((column - g.col(j)).norm(), 1e-8) << "control column " << j;
      }
    }
  }
}

TEST(BicycleModel, StepFollowsTheEquations) {
  const BicycleModel model{2.0};
  const PlanarState s = model.Step({1.0, 2.0, std::numbers::pi / 2}, {4.0, std::atan(0.5)}, 0.5);
  EXPECT_NEAR(s[kPx], 1.0, 1e-12);
  EXPECT_NEAR(s[kPy], 4.0, 1e-12);                              // + v dt along +y
  EXPECT_NEAR(s[kHeading], std::numbers::pi / 2 + 0.5, 1e-12);  // + v dt tan(delta) / L
}

}  // namespace
}  // namespace localizer::engine::experiments
