#include "engine/doa/direction_tracker.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <random>

#include "engine/doa/srp_phat.h"
#include "tests/doa/direction_peaks.h"
#include "tests/doa/plane_wave.h"

namespace localizer::engine {
namespace {

using testing::AngleBetween;
using testing::Board;
using testing::FromAzimuthElevation;
using testing::kHop_s;
using testing::PeakAt;
using testing::PlaneSource;
using testing::PlaneWaveFrame;
using testing::PlaneWaveScene;

PlaneWaveScene Circle() {
  PlaneWaveScene scene;
  scene.sensors_m = {Vec3::Zero()};
  for (int k = 0; k < 6; ++k)
    scene.sensors_m.push_back(0.0463 * Vec3(std::cos(k * std::numbers::pi / 3), std::sin(k * std::numbers::pi / 3), 0));
  return scene;
}

struct Pipeline {
  SrpPhat srp;
  DirectionTracker tracker;
};
Pipeline Make(const PlaneWaveScene& scene) {
  SrpOptions options;
  options.band_low_hz = scene.band_low_hz;
  options.band_high_hz = scene.band_high_hz;
  options.source_side = Vec3::UnitZ();
  DirectionTrackerOptions tracking;
  tracking.frame_period_s = kHop_s;
  SrpPhat srp = *SrpPhat::Create(scene.sensors_m, options);
  DirectionTracker tracker = *DirectionTracker::Create(srp.shape(), tracking);
  return {std::move(srp), std::move(tracker)};
}

// Per frame: the truths (empty direction = silent), and the confirmed tracks' ids nearest
// each truth (0: none within 0.15 rad). Counts identity switches and false-track frames.
struct Score {
  int switches = 0;
  int false_track_frames = 0;  // frames with a confirmed track near no truth
  std::vector<int> first_confirmed_frame;
};

// Two equal talkers crossing in azimuth. Asserted: the first confirmed within 3 of the first
// 5 frames, the second within 0.4 s. Printed, not yet asserted (issue 18 open): identity switches and frames with a
// confirmed track at neither talker. On this 9 cm circle the two peaks merge into one for
// about 2 s around the crossing; meanwhile weaker peaks at the hemisphere's rim (elevation
// 0) start tracks, and the coasting track of one talker drifts or is replaced. When written:
// 6 switches and 256 false-track frames in 375; with the planar peak covariance and
// precedence (direction_tracker.h) 4 and 137; with the coasting rate's decay
// (coast_rate_decay_s 0.2 s) 4 and 133.
TEST(DirectionTracker, TwoCrossingTalkersAreConfirmedAtOnce) {
  const PlaneWaveScene scene = Circle();
  Pipeline run = Make(scene);
  const int frames = 375;  // 6 s
  std::vector<uint64_t> last_id(2, 0);
  Score score;
  score.first_confirmed_frame.assign(2, -1);
  std::vector<SourceTrack> tracks;
  for (int f = 0; f < frames; ++f) {
    const double t = f * kHop_s, s = t / 6.0;
    const Vec3 a = FromAzimuthElevation(-0.6 + 1.2 * s, 0.3), b = FromAzimuthElevation(0.6 - 1.2 * s, 0.3);
    const std::vector<float> frame = PlaneWaveFrame(scene, {PlaneSource{a, 1.0}, PlaneSource{b, 1.0}}, 7000 + f);
    auto peaks = run.srp.Analyse(frame.data());
    ASSERT_TRUE(peaks.ok());
    ASSERT_TRUE(run.tracker.Update(t, *peaks, run.srp.band_power(), &tracks).ok());
    const Vec3 truths[2] = {a, b};
    bool far_from_crossing = std::abs(AngleBetween(a, b)) > 0.3;
    for (int k = 0; k < 2; ++k) {
      uint64_t id = 0;
      double best = 0.15;
      for (const SourceTrack& tr : tracks) {
        if (AngleBetween(tr.direction, truths[k]) < best) {
          best = AngleBetween(tr.direction, truths[k]);
          id = tr.id;
        }
      }
      if (id != 0 && score.first_confirmed_frame[static_cast<size_t>(k)] < 0)
        score.first_confirmed_frame[static_cast<size_t>(k)] = f;
      // A switch: away from the crossing, the truth is held by another id than before.
      if (id != 0 && far_from_crossing && last_id[static_cast<size_t>(k)] != 0 && id != last_id[static_cast<size_t>(k)])
        ++score.switches;
      if (id != 0 && far_from_crossing) last_id[static_cast<size_t>(k)] = id;
    }
    for (const SourceTrack& tr : tracks)
      score.false_track_frames += AngleBetween(tr.direction, a) > 0.15 && AngleBetween(tr.direction, b) > 0.15;
  }
  std::printf("confirmed after %d and %d frames; %d identity switches; %d false-track frames of %d\n",
              score.first_confirmed_frame[0], score.first_confirmed_frame[1], score.switches, score.false_track_frames,
              frames);
  EXPECT_GE(score.first_confirmed_frame[0], 0);
  EXPECT_LE(score.first_confirmed_frame[0], 6);  // 3 of 5 frames: 0.1 s
  EXPECT_GE(score.first_confirmed_frame[1], 0);
  // Both start in frame 0, and a frame starts at most one track (precedence,
  // direction_tracker.h): the second waits for a frame where it rises most. When written:
  // frame 17 (0.27 s).
  EXPECT_LE(score.first_confirmed_frame[1], 25);
}

TEST(DirectionTracker, ASourceThatStopsIsDeletedAndOneThatStartsIsConfirmed) {
  const PlaneWaveScene scene = Circle();
  Pipeline run = Make(scene);
  const Vec3 first = FromAzimuthElevation(0.5, 0.4), second = FromAzimuthElevation(-2.0, 0.6);
  std::vector<SourceTrack> tracks;
  std::map<uint64_t, int> frames_seen;
  int last_frame_with_first = -1, first_frame_with_second = -1;
  for (int f = 0; f < 250; ++f) {  // 4 s: the first talks 0-1.5 s, the second 2.5-4 s
    const double t = f * kHop_s;
    std::vector<PlaneSource> sources;
    if (t < 1.5) sources.push_back({first, 1.0});
    if (t >= 2.5) sources.push_back({second, 1.0});
    const std::vector<float> frame = PlaneWaveFrame(scene, sources, 9000 + f);
    auto peaks = run.srp.Analyse(frame.data());
    ASSERT_TRUE(peaks.ok());
    ASSERT_TRUE(run.tracker.Update(t, *peaks, run.srp.band_power(), &tracks).ok());
    for (const SourceTrack& tr : tracks) {
      ++frames_seen[tr.id];
      if (AngleBetween(tr.direction, first) < 0.15) last_frame_with_first = f;
      if (AngleBetween(tr.direction, second) < 0.15 && first_frame_with_second < 0) first_frame_with_second = f;
    }
  }
  const double deleted_after_s = (last_frame_with_first + 1) * kHop_s - 1.5;
  const double confirmed_after_s = first_frame_with_second * kHop_s - 2.5;
  std::printf("first deleted %.2f s after it stopped, second confirmed %.2f s after it started, %zu ids\n",
              deleted_after_s, confirmed_after_s, frames_seen.size());
  EXPECT_GT(deleted_after_s, 0.5);  // a pause shorter than max_coast_s keeps the track
  EXPECT_LT(deleted_after_s, 1.2);  // and then it goes
  EXPECT_GE(confirmed_after_s, 0.0);
  EXPECT_LT(confirmed_after_s, 0.1);
  EXPECT_EQ(frames_seen.size(), 2u);  // no other confirmed track
}

TEST(DirectionTracker, NoiseAloneConfirmsNothing) {
  PlaneWaveScene scene = Circle();
  Pipeline run = Make(scene);
  std::vector<SourceTrack> tracks;
  int confirmed_frames = 0;
  for (int f = 0; f < 1000; ++f) {  // 16 s
    const std::vector<float> frame = PlaneWaveFrame(scene, {}, 20000 + f);
    auto peaks = run.srp.Analyse(frame.data());
    ASSERT_TRUE(peaks.ok());
    ASSERT_TRUE(run.tracker.Update(f * kHop_s, *peaks, run.srp.band_power(), &tracks).ok());
    confirmed_frames += !tracks.empty();
  }
  EXPECT_EQ(confirmed_frames, 0);
}

TEST(DirectionTracker, BadOptionsAndPeaksAreNamed) {
  DirectionTrackerOptions options;
  options.peak_sigma_rad = 0.0;
  EXPECT_NE(DirectionTracker::Create(Board(), options).status().message().find("peak_sigma_rad"), std::string::npos);
  options = DirectionTrackerOptions{};
  options.min_lead_share = 1.5;
  EXPECT_NE(DirectionTracker::Create(Board(), options).status().message().find("min_lead_share"), std::string::npos);
  options = DirectionTrackerOptions{};
  options.persistent_leader_frames = -1;
  EXPECT_NE(DirectionTracker::Create(Board(), options).status().message().find("persistent_leader_frames"),
            std::string::npos);
  options = DirectionTrackerOptions{};
  options.remember_identity_s = -1.0;
  EXPECT_NE(DirectionTracker::Create(Board(), options).status().message().find("remember_identity_s"),
            std::string::npos);
  auto tracker = DirectionTracker::Create(Board(), DirectionTrackerOptions{});
  ASSERT_TRUE(tracker.ok());
  std::vector<SourceTrack> out;
  EXPECT_EQ(tracker->Update(0.0, {DirectionPeak{}}, 1.0, &out).code(), StatusCode::kInvalidArgument);  // NaN direction
}

}  // namespace
}  // namespace localizer::engine
