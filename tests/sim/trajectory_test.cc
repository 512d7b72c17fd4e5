#include "engine/sim/trajectory.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace localizer::engine {
namespace {

Trajectory Turning(double turn_rate_radps) {
  Trajectory t;
  t.position_m = Vec3(3.0, -2.0, -5.0);
  t.velocity_mps = Vec3(1.2, 1.6, 0.1);  // horizontal speed 2 m/s
  t.turn_rate_radps = turn_rate_radps;
  return t;
}

TEST(Trajectory, ConstantVelocityIsAStraightLine) {
  Trajectory t = Turning(0.0);
  for (double time_s : {-3.0, 0.0, 0.5, 17.0}) {
    const Vec3 expected = t.position_m + time_s * t.velocity_mps;
    EXPECT_LT((t.PositionAt(time_s) - expected).norm(), 1e-12) << time_s;
    EXPECT_LT((t.VelocityAt(time_s) - t.velocity_mps).norm(), 1e-15) << time_s;
  }
}

TEST(Trajectory, TurnKeepsSpeedAndTurnsAtTheGivenRate) {
  const double w = 0.2;
  Trajectory t = Turning(w);
  const double speed_mps = t.velocity_mps.norm();
  double previous_heading = std::atan2(t.velocity_mps.y(), t.velocity_mps.x());
  const double step_s = 0.1;
  for (int i = 1; i <= 100; ++i) {
    const Vec3 v = t.VelocityAt(i * step_s);
    EXPECT_NEAR(v.norm(), speed_mps, 1e-12);
    EXPECT_DOUBLE_EQ(v.z(), 0.1);
    const double heading = std::atan2(v.y(), v.x());
    const double turned = std::remainder(heading - previous_heading, 2.0 * std::numbers::pi);
    EXPECT_NEAR(turned / step_s, w, 1e-9) << "step " << i;
    previous_heading = heading;
  }
}

TEST(Trajectory, TurnVelocityIsTheDerivativeOfPosition) {
  Trajectory t = Turning(-0.35);
  const double h = 1e-4;
  for (double time_s : {-2.0, 0.0, 1.0, 9.0}) {
    const Vec3 finite_difference = (t.PositionAt(time_s + h) - t.PositionAt(time_s - h)) / (2 * h);
    // Central difference error ~ |v| w^2 h^2 / 6, far below the bound.
    EXPECT_LT((finite_difference - t.VelocityAt(time_s)).norm(), 1e-8) << time_s;
  }
}

TEST(Trajectory, TurnFollowsACircleOfRadiusSpeedOverRate) {
  const double w = 0.5;
  Trajectory t = Turning(w);
  const Vec3 v0 = t.velocity_mps;
  const double horizontal_speed = std::hypot(v0.x(), v0.y());
  // Counter-clockwise: the centre is to the left of the velocity.
  const Eigen::Vector2d centre = t.position_m.head<2>() + Eigen::Vector2d(-v0.y(), v0.x()) / w;
  for (int k = 0; k * 0.7 < 20.0; ++k) {  // 0, 0.7, ..., 19.6 s
    const double time_s = k * 0.7;
    EXPECT_NEAR((t.PositionAt(time_s).head<2>() - centre).norm(), horizontal_speed / w, 1e-12);
    EXPECT_NEAR(t.PositionAt(time_s).z(), t.position_m.z() + 0.1 * time_s, 1e-12);
  }
}

TEST(Trajectory, VanishingTurnRateGivesConstantVelocity) {
  const Trajectory straight = Turning(0.0);
  for (double w : {1e-6, 1e-9, 1e-13, -1e-300}) {
    const Trajectory t = Turning(w);
    for (double time_s : {-5.0, 0.0, 2.5, 30.0}) {
      // The turn deviates from the line by |v| w t^2 / 2.
      const double bound = 2.0 * std::abs(w) * time_s * time_s + 1e-12;
      EXPECT_LT((t.PositionAt(time_s) - straight.PositionAt(time_s)).norm(), bound) << "w " << w << " t " << time_s;
      EXPECT_TRUE(t.PositionAt(time_s).allFinite());
    }
  }
}

TEST(Trajectory, SmallTurnSeriesMatchesTheClosedForm) {
  // Either side of the 1e-4 rad switch between the series and sin/cos.
  const Trajectory t = Turning(1.0);
  for (double time_s : {0.99e-4, 1.01e-4}) {
    const double x = time_s;  // w t with w = 1
    const Vec3 v0 = t.velocity_mps;
    const double s = std::sin(x);
    const double one_minus_c = 2.0 * std::sin(0.5 * x) * std::sin(0.5 * x);
    const Vec3 expected(t.position_m.x() + v0.x() * s - v0.y() * one_minus_c,
                        t.position_m.y() + v0.x() * one_minus_c + v0.y() * s, t.position_m.z() + v0.z() * time_s);
    EXPECT_LT((t.PositionAt(time_s) - expected).norm(), 1e-15);
  }
}

}  // namespace
}  // namespace localizer::engine
