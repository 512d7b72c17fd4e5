// Per-particle speed changes (ParticleFilterOptions::speed_change_max_mps2, ParticleSet::
// SetSpeedChanges): the kinematics of a change along the velocity, and what it buys on a
// source that keeps accelerating.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "engine/filters/particle_filter.h"
#include "engine/filters/particle_set.h"
#include "tests/filters/bound_scenes.h"
#include "tests/filters/tdoa_frames.h"

namespace localizer::engine {
namespace {

// Without acceleration noise every particle keeps its heading and changes its speed at its own
// constant rate a_i: half of them hold their speed, the others spread over [-max, max]; each
// lies where its constant acceleration along the line takes it, (v0 + v) t / 2.
TEST(ParticleSpeedChanges, EachParticleSpeedsUpOrSlowsDownAlongItsHeading) {
  const ArrayGeometry array = Tetrahedron(2.0, Vec3::Zero(), 1500.0);
  const double max_mps2 = 0.8, speed_mps = 2.0, step_s = 0.1;
  const int steps = 20;
  const double t_s = steps * step_s;
  ParticleFilterOptions o = PersistentMotionOptions();
  ParticleSet set(array, o);
  set.SetSpeedChanges(max_mps2, 0.0);  // no redraws
  Vec6 start = Vec6::Zero();
  start(3) = speed_mps;
  set.SampleGaussian(start, Mat6::Zero());
  for (int k = 0; k < steps; ++k) set.Predict(step_s, 0.0);
  const auto c = set.columns();
  int held = 0;
  double slowest = speed_mps, fastest = speed_mps;
  for (int i = 0; i < o.particles; ++i) {
    const double v = c[3][i];
    ASSERT_EQ(c[4][i], 0.0f) << "particle " << i << " turned";
    ASSERT_EQ(c[5][i], 0.0f) << "particle " << i << " turned";
    ASSERT_LE(std::abs(v - speed_mps), max_mps2 * t_s + 1e-4) << "particle " << i;
    ASSERT_NEAR(c[0][i], 0.5 * (speed_mps + v) * t_s, 2e-4) << "particle " << i;
    held += v == static_cast<float>(speed_mps);
    slowest = std::min(slowest, v);
    fastest = std::max(fastest, v);
  }
  // Half hold their speed (binomial: sd 0.008 of 4096), the others reach both extremes.
  EXPECT_NEAR(static_cast<double>(held) / o.particles, ParticleSet::kSpeedHoldShare, 0.04);
  EXPECT_LT(slowest, speed_mps - 0.95 * max_mps2 * t_s);
  EXPECT_GT(fastest, speed_mps + 0.95 * max_mps2 * t_s);
}

// A particle that slows to a stop stays stopped (it does not reverse) until it redraws.
TEST(ParticleSpeedChanges, AParticleThatSlowsToAStopStaysStopped) {
  const ArrayGeometry array = Tetrahedron(2.0, Vec3::Zero(), 1500.0);
  ParticleFilterOptions o = PersistentMotionOptions();
  ParticleSet set(array, o);
  set.SetSpeedChanges(5.0, 0.0);
  Vec6 start = Vec6::Zero();
  start(4) = 0.5;  // along +y
  set.SampleGaussian(start, Mat6::Zero());
  for (int k = 0; k < 40; ++k) set.Predict(0.05, 0.0);  // 2 s: any a_i < -0.25 m/s^2 stops
  int stopped = 0;
  for (int i = 0; i < o.particles; ++i) {
    ASSERT_GE(set.columns()[4][i], 0.0f) << "particle " << i << " reversed";
    ASSERT_GE(set.columns()[1][i], 0.0f) << "particle " << i << " moved back";
    stopped += set.columns()[4][i] == 0.0f;
  }
  EXPECT_GT(stopped, o.particles / 5);  // about (1 - 0.5) x (5 - 0.25) / 10 = 24 %
}

TEST(ParticleSpeedChanges, OptionsAreValidated) {
  const ArrayGeometry array = Tetrahedron(2.0, Vec3::Zero(), 1500.0);
  ParticleFilterOptions bad = PersistentMotionOptions();
  bad.speed_change_max_mps2 = -0.1;
  EXPECT_NE(ParticleFilter::Create(array, bad).status().message().find("speed_change_max_mps2"), std::string::npos);
  bad.speed_change_max_mps2 = 21.0;
  EXPECT_NE(ParticleFilter::Create(array, bad).status().message().find("speed_change_max_mps2"), std::string::npos);
  bad.speed_change_max_mps2 = 1.0;
  bad.velocity_time_constant_s = 10.0;
  EXPECT_NE(ParticleFilter::Create(array, bad).status().message().find("constant velocity"), std::string::npos);
  EXPECT_EQ(ParticleFilterOptions{}.speed_change_max_mps2, 1.0) << "on by default (the nineteenth pass)";
  ParticleFilterOptions single = PersistentMotionOptions();
  EXPECT_FALSE(single.single_motion());
  single.SetSingleMotion();
  EXPECT_TRUE(single.single_motion());
}

// filter_bounds_test's constant-acceleration path (bound_scenes.h "ca": 0.34 m/s^2 for 12 s
// from 1.6 m/s, 4-14 m from an 8-sensor box, 2 us TDOAs), tracked with acceleration levels
// and turn rates: the quiet particles the weights prefer hold their speed and lag. With speed
// changes up to 1 m/s^2 a quiet particle can speed up with the source. Returns the RMSE after
// the first second, pooled over four seeds (the bound test's).
double AcceleratingRmse(double speed_change_max_mps2) {
  const ArrayGeometry array = testing::BoxArray();
  testing::BoundScene scene;
  scene.path = "ca";
  double se = 0.0;
  int n = 0;
  for (int seed = 1; seed <= 4; ++seed) {
    const std::vector<testing::PathPoint> path = testing::MakePath(scene, 500 + seed);
    std::mt19937_64 rng(1000 + seed);
    std::normal_distribution<double> noise(0.0, scene.sigma_s);
    ParticleFilterOptions o;  // the defaults: levels 0.003-3, turn rates up to 1 rad/s
    o.tdoa_sigma_s = scene.sigma_s;
    o.seed = seed;
    o.speed_change_max_mps2 = speed_change_max_mps2;
    auto pf = ParticleFilter::Create(array, o);
    EXPECT_TRUE(pf.ok());
    EXPECT_TRUE((*pf)->Initialise(testing::StartOf(path[0], 0.1, 0.2)).ok());
    for (int k = 1; k <= scene.steps(); ++k) {
      const double t = k * scene.dt_s;
      (*pf)->Predict(scene.dt_s);
      EXPECT_TRUE(
          (*pf)->Update(testing::TdoaFrame(array, path[k].position_m, path[k].velocity_mps, t, noise, rng)).ok());
      if (t < 1.0) continue;
      se += ((*pf)->State().mean.head<3>() - path[k].position_m).squaredNorm();
      ++n;
    }
  }
  return std::sqrt(se / n);
}

TEST(ParticleSpeedChanges, QuietParticlesFollowASourceThatKeepsAccelerating) {
  const double with = AcceleratingRmse(1.0), without = AcceleratingRmse(0.0);
  std::printf("constant acceleration: rmse %.4f m with speed changes, %.4f m without\n", with, without);
  EXPECT_LT(with, 0.8 * without);
}

}  // namespace
}  // namespace localizer::engine
