// A session's closure check (AudioSessionConfig::pair_closure, pair_closure.h) on campaign
// scenes where one reference pair of a 4-microphone array leaves the source (an echo, or a
// peak smeared by the source's motion over a 16384-sample frame at 48 kHz) and the track
// follows it, sure of itself.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>

#include "engine/pipeline/scene_campaign.h"

namespace localizer::engine {
namespace {

double SilentSeconds(uint64_t seed, bool pair_closure, SceneRow* row) {
  *row = RunRandomScene(seed, RandomSceneOptions{}, {}, /*keep_frames=*/false, [&](AudioSessionConfig* c) {
    c->pair_closure = pair_closure;
    c->pair_fusion = false;
  });
  return row->score.silent_failure_s;
}

// Campaign scenes 16000031 (floor echo, 2.2 m/s), 19000095 (0.5 m/s, 1.1 m from a 1.4 m
// array) and 8000058 (floor echo, 2 dB), in the campaign's quarter-second frames. Without the
// check each runs 10+ CRLBs off at position NEES > 50 for about a second or more (measured
// 1.5, 1.4 and 1.2 s; 1.71, 1.37 and 0.85 s with issue 20's packed transforms); with it, a
// contradicted pair is read where its witnesses agree (measured 0.0, 0.2 and 0.3 s; 0.0, 0.68
// and 0.34 s packed). Scene by scene these figures move with the transforms' last bits (a
// track near a branch point is chaotic), so the three are asserted together: they still fail
// without the check, and the check removes most of it. The check alone is tested: the fusion
// of every pair into the reference pairs (pair_fusion.h, the default since) also reads the
// cross pairs, and with both (the defaults) these scenes give 0.00, 1.71 and 0.00 s. Since a
// fresh start's first update may go in ESS-chosen stages (particle_filter.cc, thirty-second
// pass in ACCURACY.md) 16000031 no longer fails without the check either: 0.00, 1.37 and
// 1.37 s without, 0.00, 0.17 and 0.34 s with. Since a peak that association picks near the
// track states its own precision (thirty-fifth pass): 0.00, 1.37 and 1.54 s without, 0.17,
// 0.85 and 0.34 s with; the check still removes more than half. Since a pair the check moves
// onto a peak of its own states that peak's precision too (thirty-seventh pass): 0.00, 1.19
// and 1.71 s without, 0.17, 0.34 and 0.34 s with. Since acquisition solves with the cross pairs
// (thirty-eighth pass) a restart finds the source where one reference pair has left it, and
// two of the three no longer fail without the check: 1.54, 0.00 and 0.00 s without, 0.17,
// 0.00 and 0.34 s with; the sum without must still exceed a second.
TEST(PairClosureSession, APairThatLeavesTheSourceIsReadWhereTheOtherPairsAgree) {
  double with_total_s = 0.0, without_total_s = 0.0;
  for (const uint64_t seed : {16000031u, 19000095u, 8000058u}) {
    SceneRow with, without;
    const double with_s = SilentSeconds(seed, true, &with);
    const double without_s = SilentSeconds(seed, false, &without);
    ASSERT_TRUE(with.error.empty() && without.error.empty()) << with.error << without.error;
    ASSERT_NE(with.description.find("4 sensors"), std::string::npos) << "the generator changed: " << with.description;
    std::printf("%llu: silent %.2f s with the check, %.2f s without (%s)\n", static_cast<unsigned long long>(seed),
                with_s, without_s, with.description.c_str());
    EXPECT_LE(with_s, 1.0) << seed << ": a silent failure by the campaign's measure";
    EXPECT_TRUE(with.score.acquired) << seed;
    with_total_s += with_s;
    without_total_s += without_s;
  }
  EXPECT_GT(without_total_s, 1.0) << "the scenes no longer show the failure";
  EXPECT_LE(with_total_s, 0.5 * without_total_s);
}

// Campaign scene 7000015 under phat-share (4 microphones over 4.2 m in air, a source at 2.9
// m/s, two echoes): from 1.5 s on, the check moves pair 2 in most frames from its tallest peak
// onto another peak of its own ~190 samples away where its witnesses agree, nearly as tall.
// The filters read that peak at the tallest peak's SNR, up to 1.4 x too precise, and from
// 3.4 s the track sat 4 m short in range at NIS 0.2-2.4 claiming 4-6 cm: 1.19 s of silent
// failure. With the moved peak's own sigma (OwnPeakSigmaS, pair_noise.h) 0.51 s. A scene on
// the edge (a 40 % wider sigma on one pair tips it), so one bound, as the campaign's.
TEST(PairClosureSession, APairMovedOntoAPeakOfItsOwnStatesThatPeaksPrecision) {
  const SceneRow row = RunRandomScene(7000015, RandomSceneOptions{}, {}, /*keep_frames=*/false,
                                      [](AudioSessionConfig* c) { c->weighting = Weighting::kPhatShare; });
  ASSERT_TRUE(row.error.empty()) << row.error;
  ASSERT_NE(row.description.find("4 sensors over 4.24 m"), std::string::npos)
      << "the generator changed: " << row.description;
  EXPECT_GT(row.score.initialised_frames, 50);
  EXPECT_LE(row.score.silent_failure_s, 1.0) << row.description;
}

}  // namespace
}  // namespace localizer::engine
