#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "engine/sim/propagation.h"
#include "engine/sim/simulator.h"

namespace localizer::engine {
namespace {

Scenario MustMake(const std::string& name, uint64_t seed = 1) {
  StatusOr<Scenario> s = MakeScenario(name, seed);
  EXPECT_TRUE(s.ok()) << s.status().ToString();
  return std::move(s).value();
}

Vec3 Centroid(const std::vector<Vec3>& points) {
  Vec3 sum = Vec3::Zero();
  for (const Vec3& p : points) sum += p;
  return sum / static_cast<double>(points.size());
}

// Smallest and largest distance from the array centre over the whole run.
std::pair<double, double> RangeSpan(const Scenario& s) {
  const Vec3 centre = Centroid(s.sensors_m);
  double lo = 1e300;
  double hi = 0.0;
  // t = 0, 0.05, ... below duration_s: the points the former accumulating loop visited (for the
  // whole-second durations here its `t <= duration_s` missed the end by a rounding error).
  for (int k = 0; k * 0.05 < s.sim.duration_s; ++k) {
    const double t = k * 0.05;
    const double r = (s.sim.trajectory.PositionAt(t) - centre).norm();
    lo = std::min(lo, r);
    hi = std::max(hi, r);
  }
  return {lo, hi};
}

TEST(Scenarios, NamesAreTheDocumentedFour) {
  EXPECT_EQ(ScenarioNames(), (std::vector<std::string>{"tetra-water", "tetra-air", "turn-multipath", "clicks-water"}));
}

TEST(Scenarios, UnknownNameIsNotFoundAndListsTheValidOnes) {
  const StatusOr<Scenario> s = MakeScenario("tetra-mars");
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.status().code(), StatusCode::kNotFound);
  for (const std::string& name : ScenarioNames()) {
    EXPECT_NE(s.status().message().find(name), std::string::npos) << s.status().message();
  }
}

TEST(Scenarios, EveryScenarioBuildsAnArrayAndSimulates) {
  for (const std::string& name : ScenarioNames()) {
    Scenario s = MustMake(name, 9);
    EXPECT_EQ(s.name, name);
    EXPECT_FALSE(s.description.empty());
    EXPECT_EQ(s.sim.seed, 9u);
    EXPECT_TRUE(s.sim.Validate().ok()) << name << ": " << s.sim.Validate().ToString();
    StatusOr<ArrayGeometry> array = ArrayGeometry::Create(s.sensors_m, s.sound_speed_mps);
    ASSERT_TRUE(array.ok()) << name << ": " << array.status().ToString();
    s.sim.duration_s = 1.0;  // keeps the test fast
    StatusOr<SimResult> r = Simulate(*array, s.sim);
    ASSERT_TRUE(r.ok()) << name << ": " << r.status().ToString();
    EXPECT_EQ(r->channel_count, static_cast<int>(s.sensors_m.size()));
    EXPECT_EQ(r->samples_per_channel, std::llround(s.sim.sample_rate_hz));
    float peak = 0.0f;
    for (float v : r->samples) {
      ASSERT_TRUE(std::isfinite(v)) << name;
      peak = std::max(peak, std::abs(v));
    }
    EXPECT_GT(peak, 0.0f) << name;
    EXPECT_EQ(r->truth.size(), 101u) << name;
  }
}

TEST(Scenarios, UnderwaterScenesAreBelowTheSurface) {
  for (const char* name : {"tetra-water", "turn-multipath", "clicks-water"}) {
    const Scenario s = MustMake(name);
    EXPECT_EQ(s.sound_speed_mps, 1500.0);
    EXPECT_EQ(s.sim.sample_rate_hz, 11025.0);
    for (const Vec3& m : s.sensors_m) EXPECT_LT(m.z(), 0.0) << name;
    for (int k = 0; k * 0.5 <= s.sim.duration_s; ++k) {
      const double t = k * 0.5;
      EXPECT_LT(s.sim.trajectory.PositionAt(t).z(), 0.0) << name << " at " << t;
    }
  }
}

TEST(Scenarios, TetraWaterTrackStaysFourToFifteenMetresAway) {
  const Scenario s = MustMake("tetra-water");
  EXPECT_EQ(s.sensors_m.size(), 4u);
  EXPECT_NEAR((s.sensors_m[0] - s.sensors_m[1]).norm(), 2.0, 1e-12);
  EXPECT_LT((Centroid(s.sensors_m) - Vec3(0, 0, -10)).norm(), 1e-12);
  const Vec3 centre = Centroid(s.sensors_m);
  EXPECT_NEAR((s.sim.trajectory.position_m - centre).norm(), 8.0, 0.1);
  const auto [closest, farthest] = RangeSpan(s);
  EXPECT_GE(closest, 4.0);
  EXPECT_LE(farthest, 15.0);
  EXPECT_EQ(s.sim.trajectory.turn_rate_radps, 0.0);
  EXPECT_NEAR(s.sim.trajectory.position_m.z(), -8.0, 1e-12);
  EXPECT_EQ(s.sim.duration_s, 20.0);
  EXPECT_EQ(s.sim.snr_db, 20.0);
}

TEST(Scenarios, TetraAirTalkerWalksTwoToFourMetresAway) {
  const Scenario s = MustMake("tetra-air");
  EXPECT_EQ(s.sound_speed_mps, 343.0);
  EXPECT_EQ(s.sim.sample_rate_hz, 48000.0);
  EXPECT_NEAR((s.sensors_m[2] - s.sensors_m[3]).norm(), 0.5, 1e-12);
  EXPECT_NEAR(Centroid(s.sensors_m).z(), 1.5, 1e-12);
  EXPECT_NEAR(Speed(s.sim.trajectory), 1.0, 1e-12);
  const auto [closest, farthest] = RangeSpan(s);
  EXPECT_GE(closest, 2.0);
  EXPECT_LE(farthest, 4.0);
}

TEST(Scenarios, TurnMultipathTurnsHalfACircleWithASurfaceEcho) {
  const Scenario s = MustMake("turn-multipath");
  EXPECT_EQ(s.sensors_m.size(), 8u);
  const Trajectory& t = s.sim.trajectory;
  EXPECT_NEAR(Speed(t), 2.0, 1e-12);
  EXPECT_NEAR(t.turn_rate_radps * s.sim.duration_s, std::numbers::pi, 1e-12);
  EXPECT_TRUE(s.sim.surface_reflection_enabled);
  EXPECT_EQ(s.sim.surface_reflection, -0.9);
  EXPECT_EQ(s.sim.snr_db, 5.0);
  const auto [closest, farthest] = RangeSpan(s);
  EXPECT_NEAR(closest, 11.1, 0.1);
  EXPECT_LT(farthest, 22.0);
}

TEST(Scenarios, ClicksWaterSharesTetraWatersGeometryAndTrack) {
  const Scenario clicks = MustMake("clicks-water");
  const Scenario broadband = MustMake("tetra-water");
  EXPECT_EQ(clicks.sim.signal, SourceSignal::kClicks);
  EXPECT_EQ(clicks.sim.click_rate_hz, 20.0);
  EXPECT_EQ(clicks.sensors_m, broadband.sensors_m);
  EXPECT_EQ(clicks.sim.trajectory.position_m, broadband.sim.trajectory.position_m);
  EXPECT_EQ(clicks.sim.trajectory.velocity_mps, broadband.sim.trajectory.velocity_mps);
}

}  // namespace
}  // namespace localizer::engine
