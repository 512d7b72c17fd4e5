// Every pair folded into the reference pairs' delays (pair_fusion.h) through whole sessions:
// on campaign scenes the development never used, larger arrays' tracks land nearer the truth
// with the fusion than without it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <vector>

#include "engine/pipeline/scene_campaign.h"
#include "engine/sim/random_scene.h"

namespace localizer::engine {
namespace {

// The first twenty Gaussian scenes of draw 90 with at least 6 sensors, 12 s each (the
// campaign's). With M sensors the fused delays have about 2 / M of one pair's variance where
// noise dominates the GCC (tests/tdoa/pair_fusion_test.cc: x 0.64 in sd at 7 sensors), so the
// tracks' median error should fall by well over 10 %: the test asks for the median per-scene
// ratio below 0.9, and no scene acquired without the fusion lost with it. Measured: 0.71, 16 of
// 20 scenes nearer (campaign draws 1-10, 336 such scenes: 0.68, 272 nearer). Single scenes
// scatter: the first ten of the same draw cut to 8 s gave 0.93, 5 of 10 nearer.
TEST(PairFusionSession, LargerArraysTrackNearerTheTruthOnScenesNeverUsedInDevelopment) {
  RandomSceneOptions options;
  options.duration_s = 12.0;
  options.scene_class = SceneClass::kGaussian;
  std::vector<double> ratios;
  for (uint64_t i = 0; ratios.size() < 20 && i < 400; ++i) {
    const uint64_t seed = 90000000 + i;
    const StatusOr<RandomScene> scene = DrawRandomScene(seed, options);
    ASSERT_TRUE(scene.ok()) << scene.status().message();
    if (scene->scenario.sensors_m.size() < 6) continue;
    const SceneRow with = RunRandomScene(seed, options);
    const SceneRow without =
        RunRandomScene(seed, options, {}, /*keep_frames=*/false, [](AudioSessionConfig* c) { c->pair_fusion = false; });
    ASSERT_TRUE(with.error.empty() && without.error.empty()) << with.error << without.error;
    if (without.score.acquired) {
      EXPECT_TRUE(with.score.acquired) << seed << ": " << with.description;
    }
    if (!with.score.acquired || !without.score.acquired || !(without.score.median_error_m > 0.0)) continue;
    const double ratio = with.score.median_error_m / without.score.median_error_m;
    std::printf("%llu: median error %.4f m with the fusion, %.4f m without (x %.2f; %s)\n",
                static_cast<unsigned long long>(seed), with.score.median_error_m, without.score.median_error_m, ratio,
                with.description.c_str());
    ratios.push_back(ratio);
  }
  ASSERT_EQ(ratios.size(), 20u);
  std::sort(ratios.begin(), ratios.end());
  const double median = 0.5 * (ratios[9] + ratios[10]);
  std::printf("median per-scene ratio %.3f\n", median);
  EXPECT_LT(median, 0.9);
}

}  // namespace
}  // namespace localizer::engine
