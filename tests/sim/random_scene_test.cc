#include "engine/sim/random_scene.h"

#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <set>

namespace localizer::engine {
namespace {

constexpr double kDurationS = 12.0;

// What every drawn scene promises (random_scene.h), over many seeds: drawing is cheap.
TEST(RandomScene, DrawsStayInTheirStatedRanges) {
  std::set<SceneClass> classes;
  std::set<size_t> sizes;
  std::set<std::string> media;
  for (uint64_t seed = 1; seed <= 300; ++seed) {
    auto drawn = DrawRandomScene(seed);
    ASSERT_TRUE(drawn.ok()) << seed << ": " << drawn.status().ToString();
    const RandomScene& s = *drawn;
    const SimOptions& o = s.scenario.sim;
    classes.insert(s.scene_class);
    media.insert(s.medium);
    const std::vector<Vec3>& m = s.scenario.sensors_m;
    sizes.insert(m.size());
    ASSERT_TRUE(m.size() == 4 || (m.size() >= 6 && m.size() <= 8)) << seed;
    EXPECT_GE(s.aperture_m, 0.2 - 1e-9);
    EXPECT_LE(s.aperture_m, 40.0 + 1e-9);
    auto array = ArrayGeometry::Create(m, s.scenario.sound_speed_mps);
    ASSERT_TRUE(array.ok()) << seed << ": " << array.status().ToString();
    EXPECT_NEAR(array->aperture_m(), s.aperture_m, 1e-6 * s.aperture_m) << seed;
    // Not coplanar: the thinnest principal spread is a fair share of the widest.
    Eigen::MatrixXd centred(m.size(), 3);
    for (size_t i = 0; i < m.size(); ++i) centred.row(i) = (m[i] - array->centroid_m()).transpose();
    const Eigen::Vector3d sv = Eigen::JacobiSVD<Eigen::MatrixXd>(centred).singularValues();
    EXPECT_GE(sv(2) / sv(0), 0.2 - 1e-9) << seed;
    const double range_apertures = s.start_range_m / s.aperture_m;
    EXPECT_GE(range_apertures, 0.3 - 1e-9) << seed;
    EXPECT_LE(range_apertures, 5.0 + 1e-9) << seed;
    EXPECT_LE(o.trajectory.velocity_mps.norm(), 5.0) << seed;
    EXPECT_LT(o.trajectory.velocity_mps.norm(), 0.3 * s.scenario.sound_speed_mps);
    EXPECT_GE(o.snr_db, -5.0);
    EXPECT_LE(o.snr_db, 20.0);
    EXPECT_EQ(o.duration_s, kDurationS);
    EXPECT_EQ(o.seed, seed);
    EXPECT_TRUE(o.Validate().ok()) << seed;
    if (s.medium == "water") {
      EXPECT_EQ(s.scenario.sound_speed_mps, 1500.0);
      EXPECT_TRUE(o.sample_rate_hz == 11025.0 || o.sample_rate_hz == 16000.0);
      for (const Vec3& p : m) EXPECT_LT(p.z(), 0.0) << seed;  // below the surface
      for (int k = 0; k * 0.5 <= kDurationS; ++k) EXPECT_LT(o.trajectory.PositionAt(k * 0.5).z(), 0.0) << seed;
    } else {
      EXPECT_EQ(s.scenario.sound_speed_mps, 343.0);
      EXPECT_TRUE(o.sample_rate_hz == 16000.0 || o.sample_rate_hz == 48000.0);
      EXPECT_LE(s.aperture_m, 5.0 + 1e-9);
    }
    const bool echoes = o.surface_reflection_enabled || o.bottom_reflection_enabled;
    EXPECT_EQ(echoes, s.scene_class == SceneClass::kMultipath) << seed;
    EXPECT_EQ(o.impulse_probability > 0.0, s.scene_class == SceneClass::kImpulsive) << seed;
  }
  EXPECT_EQ(classes.size(), 3u);
  EXPECT_EQ(media.size(), 2u);
  EXPECT_EQ(sizes.size(), 4u);  // 4, 6, 7, 8
}

TEST(RandomScene, SameSeedSameSceneAndAForcedClassChangesOnlyItsParts) {
  const RandomScene a = *DrawRandomScene(77);
  const RandomScene b = *DrawRandomScene(77);
  EXPECT_EQ(a.scenario.description, b.scenario.description);
  for (size_t i = 0; i < a.scenario.sensors_m.size(); ++i) EXPECT_EQ(a.scenario.sensors_m[i], b.scenario.sensors_m[i]);
  EXPECT_EQ(a.scenario.sim.trajectory.position_m, b.scenario.sim.trajectory.position_m);
  EXPECT_NE(DrawRandomScene(78)->scenario.description, a.scenario.description);
  RandomSceneOptions options;
  options.scene_class = SceneClass::kImpulsive;
  const RandomScene forced = *DrawRandomScene(77, options);
  EXPECT_EQ(forced.scene_class, SceneClass::kImpulsive);
  EXPECT_GT(forced.scenario.sim.impulse_probability, 0.0);
  EXPECT_EQ(forced.scenario.sensors_m, a.scenario.sensors_m);
  EXPECT_EQ(forced.scenario.sim.trajectory.velocity_mps, a.scenario.sim.trajectory.velocity_mps);
  EXPECT_EQ(forced.scenario.sim.snr_db, a.scenario.sim.snr_db);
}

TEST(RandomScene, BadOptionsAndClassNames) {
  RandomSceneOptions options;
  options.duration_s = 0.0;
  EXPECT_EQ(DrawRandomScene(1, options).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(*ParseSceneClass("multipath"), SceneClass::kMultipath);
  EXPECT_FALSE(ParseSceneClass("rain").ok());
}

}  // namespace
}  // namespace localizer::engine
