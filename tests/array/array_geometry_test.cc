#include "engine/array/array_geometry.h"

#include <gtest/gtest.h>

namespace localizer::engine {
namespace {

std::vector<Vec3> Tetrahedron() { return {Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 2, 0), Vec3(0, 0, 2)}; }

TEST(ArrayGeometry, RejectsFewerThanFourSensors) {
  auto g = ArrayGeometry::Create({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)}, 1500.0);
  ASSERT_FALSE(g.ok());
  EXPECT_EQ(g.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(g.status().message().find("at least 4"), std::string::npos);
}

TEST(ArrayGeometry, RejectsCoplanarAndCoincidentSensors) {
  auto planar =
      ArrayGeometry::Create({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0), Vec3(0.5, 0.2, 1e-5)}, 1500.0);
  ASSERT_FALSE(planar.ok());
  EXPECT_NE(planar.status().message().find("coplanar"), std::string::npos);
  auto same = ArrayGeometry::Create({Vec3(0, 0, 0), Vec3(0, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)}, 1500.0);
  ASSERT_FALSE(same.ok());
  EXPECT_NE(same.status().message().find("coincide"), std::string::npos);
}

TEST(ArrayGeometry, RejectsBadSoundSpeedAndReference) {
  EXPECT_FALSE(ArrayGeometry::Create(Tetrahedron(), 0.0).ok());
  EXPECT_FALSE(ArrayGeometry::Create(Tetrahedron(), 1500.0, 4).ok());
}

TEST(ArrayGeometry, KnownGeometryGivesKnownDelays) {
  auto g = ArrayGeometry::Create(Tetrahedron(), 1500.0);
  ASSERT_TRUE(g.ok());
  // Source on the x axis far beyond sensor 1: sensor 1 is 2 m nearer than the reference.
  const Vec3 s(1000.0, 0.0, 0.0);
  const Eigen::VectorXd h = g->Tdoa(s);
  EXPECT_NEAR(h(0), -2.0 / 1500.0, 1e-8);
  // Sensors 2 and 3 are at the same range from s, sqrt(1000^2 + 4) - 1000 farther.
  EXPECT_NEAR(h(1), (std::sqrt(1000.0 * 1000.0 + 4.0) - 1000.0) / 1500.0, 1e-12);
  EXPECT_NEAR(h(2), h(1), 1e-15);
  EXPECT_NEAR(g->max_delay_s(0), 2.0 / 1500.0, 1e-15);
}

// pair_of_sensor inverts sensor_of_pair whatever the reference, and a pair of two
// non-reference sensors (a, b) has the delay Tdoa(pair of b) - Tdoa(pair of a) = t_b - t_a
// (how acquisition reads the cross pairs, lag_field.h).
TEST(ArrayGeometry, PairOfSensorInvertsSensorOfPairForAnyReference) {
  for (int ref = 0; ref < 4; ++ref) {
    const auto g = *ArrayGeometry::Create(Tetrahedron(), 1500.0, ref);
    EXPECT_EQ(g.pair_of_sensor(ref), -1);
    for (int p = 0; p < g.pair_count(); ++p) EXPECT_EQ(g.pair_of_sensor(g.sensor_of_pair(p)), p);
    const Vec3 s(3.0, -1.0, 2.5);
    const Eigen::VectorXd h = g.Tdoa(s);
    for (int a = 0; a < 4; ++a) {
      for (int b = 0; b < 4; ++b) {
        if (a == ref || b == ref) continue;
        EXPECT_NEAR(h(g.pair_of_sensor(b)) - h(g.pair_of_sensor(a)), g.TravelTime(s, b) - g.TravelTime(s, a), 1e-12);
      }
    }
  }
}

TEST(ArrayGeometry, JacobianMatchesFiniteDifferences) {
  auto g = ArrayGeometry::Create(Tetrahedron(), 343.0, 2);
  ASSERT_TRUE(g.ok());
  const Vec3 s(3.0, -4.0, 1.5);
  const Eigen::MatrixXd jac = g->TdoaJacobian(s);
  for (int axis = 0; axis < 3; ++axis) {
    Vec3 step = Vec3::Zero();
    step(axis) = 1e-6;
    const Eigen::VectorXd fd = (g->Tdoa(s + step) - g->Tdoa(s - step)) / 2e-6;
    for (int p = 0; p < g->pair_count(); ++p) EXPECT_NEAR(jac(p, axis), fd(p), 1e-9);
  }
  EXPECT_EQ(g->sensor_of_pair(0), 0);
  EXPECT_EQ(g->sensor_of_pair(2), 3);
}

TEST(ArrayGeometry, DelaysNeverExceedTheirPhysicalMaximum) {
  auto g = ArrayGeometry::Create(Tetrahedron(), 1500.0);
  ASSERT_TRUE(g.ok());
  for (int i = 0; i <= 8; ++i)  // x, y = -10, -7.5, ..., 10
    for (int j = 0; j <= 8; ++j) {
      const double x = -10.0 + 2.5 * i, y = -10.0 + 2.5 * j;
      const Eigen::VectorXd h = g->Tdoa(Vec3(x, y, -3.0));
      for (int p = 0; p < g->pair_count(); ++p) EXPECT_LE(std::abs(h(p)), g->max_delay_s(p) + 1e-15);
    }
}

}  // namespace
}  // namespace localizer::engine
