// Direction tracks in a reverberant room (engine/sim/room.h): two talkers in bursts around a
// ReSpeaker-style board, RT60 0.4 s (the issue-18 goal scene of tests/bench/doa_room_report,
// shorter and with its own seed). What is asserted is what a user of the tracks sees: time of
// confirmed or coasting track away from both talkers (reflections taken for sources), and
// the share of sounding talker-frames with a track on the talker.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <set>

#include "engine/doa/direction_tracker.h"
#include "engine/doa/srp_phat.h"
#include "engine/sim/room.h"

namespace localizer::engine {
namespace {

constexpr double kFs = 16000.0;
constexpr int kFrame = 512, kHop = 256;

double Wrap(double a) { return std::remainder(a, 2.0 * std::numbers::pi); }

struct RoomScore {
  double false_track_s_per_min = 0.0;
  double tracked_share = 0.0;  // of sounding talker-frames
  int ids = 0;                 // distinct identities reported
};

RoomScore RunRoom(bool start_at_onsets_only, uint64_t seed, double resume_after_s = 0.0,
                  bool continue_identities = false,
                  double coast_rate_decay_s = DirectionTrackerOptions{}.coast_rate_decay_s, bool leading = false) {
  const Vec3 centre(2.2, 1.9, 1.0);
  const double a = 0.0405;
  std::vector<Vec3> board, relative{Vec3(a, 0, 0), Vec3(0, a, 0), Vec3(-a, 0, 0), Vec3(0, -a, 0)};
  for (const Vec3& m : relative) board.push_back(centre + m);
  const int64_t samples = static_cast<int64_t>(10.0 * kFs);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  ShoeboxRoom room;
  room.rt60_s = 0.4;
  std::vector<RoomSource> sources(2);
  std::vector<double> azimuths(2);
  std::vector<std::vector<bool>> on(2, std::vector<bool>(static_cast<size_t>(samples), false));
  for (int k = 0; k < 2; ++k) {
    azimuths[k] = Wrap(-1.0 + k * std::numbers::pi / 2);
    const double range = 1.5 + uniform(rng), height = 0.3 + 0.2 * uniform(rng);
    sources[k].position_m = centre + Vec3(range * std::cos(azimuths[k]), range * std::sin(azimuths[k]), height);
    for (int64_t i = 0; i < samples;) {  // bursts of 0.4-1.5 s, pauses of 0.2-1.0 s
      const auto burst = static_cast<int64_t>((0.4 + 1.1 * uniform(rng)) * kFs);
      const auto pause = static_cast<int64_t>((0.2 + 0.8 * uniform(rng)) * kFs);
      for (int64_t j = i; j < std::min(samples, i + burst); ++j) on[k][static_cast<size_t>(j)] = true;
      i += burst + pause;
    }
    sources[k].signal.resize(static_cast<size_t>(samples));
    for (int64_t i = 0; i < samples; ++i)
      sources[k].signal[static_cast<size_t>(i)] = on[k][static_cast<size_t>(i)] ? normal(rng) : 0.0;
  }
  auto signals = RenderInRoom(room, sources, board, kFs, samples);
  EXPECT_TRUE(signals.ok());
  if (!signals.ok()) return {};
  const double direct = 1.0 / (4.0 * std::numbers::pi * 2.0);  // a talker at 2 m
  for (float& v : *signals) v += static_cast<float>(direct * std::pow(10.0, -15.0 / 20.0) * normal(rng));

  SrpOptions options;
  options.band_low_hz = 100.0;
  options.band_high_hz = 7000.0;
  options.source_side = Vec3::UnitZ();
  options.hop_samples = kHop;
  auto srp = SrpPhat::Create(relative, options);
  DirectionTrackerOptions tracking;
  tracking.frame_period_s = kHop / kFs;
  tracking.start_at_onsets_only = start_at_onsets_only;
  tracking.resume_after_s = resume_after_s;
  tracking.continue_identities = continue_identities;
  tracking.coast_rate_decay_s = coast_rate_decay_s;
  if (!leading) tracking.min_lead_frames = 0, tracking.min_lead_share = 0.0;  // the stack the first tests measured
  tracking.remember_identity_s = 0.0;     // later than every rule these tests measure
  tracking.persistent_leader_frames = 0;  // so is this
  EXPECT_TRUE(srp.ok());
  auto tracker = DirectionTracker::Create(srp->shape(), tracking);
  EXPECT_TRUE(tracker.ok());
  const double near_rad = 20.0 * std::numbers::pi / 180.0;
  int frames = 0, false_frames = 0, sounding = 0, tracked = 0;
  std::set<uint64_t> ids;
  std::vector<float> frame(4 * kFrame);
  std::vector<SourceTrack> tracks;
  for (int64_t start = 0; start + kFrame <= samples; start += kHop, ++frames) {
    for (int m = 0; m < 4; ++m) std::copy_n(signals->begin() + m * samples + start, kFrame, frame.begin() + m * kFrame);
    auto peaks = srp->Analyse(frame.data());
    EXPECT_TRUE(peaks.ok());
    EXPECT_TRUE(tracker->Update(static_cast<double>(start) / kFs, *peaks, srp->band_power(), &tracks).ok());
    for (int k = 0; k < 2; ++k) {
      if (!on[k][static_cast<size_t>(start)] || !on[k][static_cast<size_t>(start + kFrame - 1)]) continue;
      ++sounding;
      for (const SourceTrack& tr : tracks) {
        if (std::abs(Wrap(tr.azimuth_rad - azimuths[k])) < near_rad) {
          ++tracked;
          break;
        }
      }
    }
    for (const SourceTrack& tr : tracks) ids.insert(tr.id);
    for (const SourceTrack& tr : tracks)
      false_frames += std::abs(Wrap(tr.azimuth_rad - azimuths[0])) >= near_rad &&
                      std::abs(Wrap(tr.azimuth_rad - azimuths[1])) >= near_rad;
  }
  RoomScore score;
  score.false_track_s_per_min = false_frames * kHop / kFs / (frames * kHop / kFs / 60.0);
  score.tracked_share = static_cast<double>(tracked) / std::max(1, sounding);
  score.ids = static_cast<int>(ids.size());
  return score;
}

// The same scene with and without precedence (start_at_onsets_only false: every unexplained
// peak starts a track, as before it), both without the resume rule (resume_after_s 0). When
// written: 52 s of false track per minute and 92.7 % of sounding talker-frames tracked with
// it, 377 s and 99.5 % without; since the removal weighted by each bin's signal share
// (pair_spectra.h): 62.5 s and 88.5 % with it, 375.5 s and 99.5 % without; with identities
// continued (the default since): 54.6 s and 88.5 %, 394.2 s and 99.5 %; with the coasting
// rate's decay (coast_rate_decay_s 0.2 s, the default since): 10.8 s and 92.8 %, 331.1 s and
// 99.5 %. Asserted: with it at
// most 100 s per minute and at most a quarter of the figure without it, at least 88 %
// tracked; without it over 200 s per minute (the reflections are there to be taken). The
// issue's goal (1 s per minute) is not met; see ACCURACY.md.
TEST(DirectionTrackerRoom, ReflectionsStartNoTracksAtRt60OfPoint4) {
  const RoomScore with = RunRoom(true, 7);
  const RoomScore without = RunRoom(false, 7);
  std::printf("precedence: %.1f s/min false, %.1f %% tracked; without: %.1f s/min false, %.1f %% tracked\n",
              with.false_track_s_per_min, 100.0 * with.tracked_share, without.false_track_s_per_min,
              100.0 * without.tracked_share);
  EXPECT_LE(with.false_track_s_per_min, 100.0);
  EXPECT_LE(with.false_track_s_per_min, 0.25 * without.false_track_s_per_min);
  EXPECT_GE(with.tracked_share, 0.88);
  EXPECT_GT(without.false_track_s_per_min, 200.0);
}

// The resume rule on top of precedence (the default 0.25 s: a track silent that long takes
// only a peak that rose): a paused talker's coasting track no longer takes the other
// talker's reflections. When written: 25.6 s/min false and 88.5 % tracked with it, 52.4 and
// 92.7 % without (a resuming talker whose rise does not pass the threshold waits for its
// next onset: the rule's cost); since the removal weighted by each bin's signal share
// (pair_spectra.h): 17.4 and 88.6 %, 62.5 and 88.5 %; with identities continued: 17.4 and 88.6 %,
// 54.6 and 88.5 %; with the coasting rate's decay: 0.0 and 93.0 %, 10.8 and 92.8 %.
// Asserted: at most 0.6 x the false time of precedence alone,
// and at most 6 points less tracked.
TEST(DirectionTrackerRoom, ASilentTrackResumesOnlyOnARisingPeak) {
  const RoomScore without = RunRoom(true, 7, 0.0);
  const RoomScore with = RunRoom(true, 7, DirectionTrackerOptions{}.resume_after_s);
  std::printf("resume rule: %.1f s/min false, %.1f %% tracked; without: %.1f s/min false, %.1f %% tracked\n",
              with.false_track_s_per_min, 100.0 * with.tracked_share, without.false_track_s_per_min,
              100.0 * without.tracked_share);
  EXPECT_LE(with.false_track_s_per_min, 0.6 * without.false_track_s_per_min);
  EXPECT_GE(with.tracked_share, without.tracked_share - 0.06);
}

// Identities continued (the default; direction_tracker.h, "Identities"), on top of the
// resume rule: a talker's track drawn off during its pause (coasting on its rate estimate, or
// taking the other talker's reflections) is replaced, when the talker resumes, by a track that
// takes its identity, and is no longer reported. Asserted: less false time than without, at
// most 1 point less tracked, and fewer identities reported (two talkers). Measured with the
// coasting rate's decay off (coast_rate_decay_s 0, as when written): with it the drift this
// rule repairs no longer happens in this scene (0.0 s/min false either way, 93.0 % tracked,
// 3 identities against 4), so there would be nothing to compare.
TEST(DirectionTrackerRoom, ATalkerResumingKeepsItsIdentityAndItsOldTrackGoes) {
  const double resume_s = DirectionTrackerOptions{}.resume_after_s;
  const RoomScore without = RunRoom(true, 7, resume_s, false, 0.0);
  const RoomScore with = RunRoom(true, 7, resume_s, true, 0.0);
  std::printf(
      "identities continued: %.1f s/min false, %.1f %% tracked, %d ids; without: %.1f s/min false, %.1f %% "
      "tracked, %d ids\n",
      with.false_track_s_per_min, 100.0 * with.tracked_share, with.ids, without.false_track_s_per_min,
      100.0 * without.tracked_share, without.ids);
  EXPECT_LT(with.false_track_s_per_min, without.false_track_s_per_min);
  EXPECT_GE(with.tracked_share, without.tracked_share - 0.01);
  EXPECT_LT(with.ids, without.ids);
}

// Leading (direction_tracker.h): tracks that seldom take their frame's strongest peak are not
// reported. Measured with precedence off (every unexplained peak starts a track), so that the
// room's reflections hold tracks to be judged; the other rules at their defaults (deleted
// tracks' identities not remembered). When
// written: 55.4 s/min false and 95.1 % tracked with it, 207.4 and 99.5 % without. Asserted: at
// most 0.4 x the false time, at most 5 points less tracked.
TEST(DirectionTrackerRoom, TracksThatSeldomLeadTheirFrameAreNotReported) {
  const DirectionTrackerOptions defaults;
  const RoomScore without = RunRoom(false, 7, defaults.resume_after_s, true, defaults.coast_rate_decay_s, false);
  const RoomScore with = RunRoom(false, 7, defaults.resume_after_s, true, defaults.coast_rate_decay_s, true);
  std::printf("leading: %.1f s/min false, %.1f %% tracked; without: %.1f s/min false, %.1f %% tracked\n",
              with.false_track_s_per_min, 100.0 * with.tracked_share, without.false_track_s_per_min,
              100.0 * without.tracked_share);
  EXPECT_LE(with.false_track_s_per_min, 0.4 * without.false_track_s_per_min);
  EXPECT_GE(with.tracked_share, without.tracked_share - 0.05);
}

}  // namespace
}  // namespace localizer::engine
