// The mirror watch (mirror_watch.h): the other exact solution of a 4-sensor array's TDOAs is
// followed and called live while it moves as a source can, inside the allowed region and
// apart from the track, also after the track jumps onto it; a mirror that jumps, one outside
// the region, and arrays of other sizes are not.
#include "engine/pipeline/mirror_watch.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <optional>
#include <random>

#include "engine/array/multilateration.h"
#include "tests/filters/tdoa_frames.h"

namespace localizer::engine {
namespace {

constexpr double kHopS = 0.128;
constexpr double kSigmaS = 2e-6;

struct Walk {
  ArrayGeometry array;
  Vec3 start_m;
  Vec3 velocity_mps;
};

// A 20 m tetrahedron in water and a source 50 m out (walking at 1 m/s across its line of
// sight where a test says so), on the first of a fixed list of bearings whose TDOAs have a
// second exact solution at least 10 m away.
Walk FindWalk() {
  Walk w{Tetrahedron(20.0, Vec3::Zero(), 1500.0), Vec3::Zero(), Vec3::Zero()};
  for (double az = 0.1; az < 6.2; az += 0.3) {
    for (double el : {-0.6, -0.2, 0.2, 0.6}) {
      const Vec3 at = 50.0 * Vec3(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
      for (const Vec3& c : ClosedFormCandidates(w.array, w.array.Tdoa(at))) {
        if ((w.array.Tdoa(c) - w.array.Tdoa(at)).norm() < 1e-9 && (c - at).norm() > 10.0) {
          w.start_m = at;
          w.velocity_mps = at.cross(Vec3::UnitZ()).normalized();  // across the line of sight
          return w;
        }
      }
    }
  }
  return w;
}

Mat3 TrackCovariance(const ArrayGeometry& array, const Vec3& at_m) { return TdoaPositionCrlb(array, at_m, kSigmaS); }

// Feeds `frames` frames of the walk (position from `track_at(frame)`) and returns the live
// mirror after each.
template <typename TrackAt>
std::vector<std::optional<MirrorWatch::Mirror>> Follow(const ArrayGeometry& array, int frames, TrackAt track_at,
                                                       const MirrorWatch::Region& region = {}) {
  MirrorWatch watch(1.0);
  std::vector<std::optional<MirrorWatch::Mirror>> live;
  const Eigen::VectorXd sigma_s = Eigen::VectorXd::Constant(array.pair_count(), kSigmaS);
  for (int f = 0; f < frames; ++f) {
    const Vec3 p = track_at(f);
    watch.Update(array, f * kHopS, p, TrackCovariance(array, p), Eigen::VectorXd(), sigma_s, kSigmaS, region);
    live.push_back(watch.Live());
  }
  return live;
}

// The other exact root of the track's TDOAs, exact to a thousandth of a sigma and far away
// (or nothing when there is none).
std::optional<Vec3> OtherRoot(const ArrayGeometry& array, const Vec3& at_m) {
  for (const Vec3& c : ClosedFormCandidates(array, array.Tdoa(at_m))) {
    if ((array.Tdoa(c) - array.Tdoa(at_m)).cwiseAbs().maxCoeff() < 1e-3 * kSigmaS && (c - at_m).norm() > 10.0) return c;
  }
  return std::nullopt;
}

// A still source: its mirror stands still too, which no motion can rule out. Live from the
// first frame: until its filter can test it, nothing tells the mirror from the source.
TEST(MirrorWatch, AStillSourcesMirrorIsLiveFromTheFirstFrame) {
  const Walk w = FindWalk();
  ASSERT_GT(w.start_m.norm(), 0.0) << "no bearing of the list has a second exact solution";
  const auto at = [&](int) { return w.start_m; };
  const auto live = Follow(w.array, 30, at);
  for (int f = 0; f < 30; ++f) {
    ASSERT_TRUE(live[f]) << "frame " << f;
    EXPECT_LT((live[f]->position_m - *OtherRoot(w.array, w.start_m)).norm(), 1e-6);
    EXPECT_GT(live[f]->covariance_m2.trace(), 0.0);
  }
}

// Walking at 1 m/s across the line of sight, this source's mirror races away at 80 m/s and
// more (the two solutions part as the geometry changes): no source moves so. The mirror counts
// until its filter can test it (kMinLiveFrames updates) and is ruled out from then on. The
// dynamics tell the two apart here, as they would for the particle filter.
TEST(MirrorWatch, AMirrorThatRacesAwayIsRuledOutOnceItsFilterCanTestIt) {
  const Walk w = FindWalk();
  const auto at = [&](int f) { return Vec3(w.start_m + w.velocity_mps * (f * kHopS)); };
  ASSERT_TRUE(OtherRoot(w.array, at(0)) && OtherRoot(w.array, at(1)));
  const double mirror_speed_mps = (*OtherRoot(w.array, at(1)) - *OtherRoot(w.array, at(0))).norm() / kHopS;
  ASSERT_GT(mirror_speed_mps, 20.0) << "the geometry changed: the mirror no longer races away";
  const auto live = Follow(w.array, 30, at);
  EXPECT_TRUE(live[0]) << "untested, the mirror counts";
  for (int f = MirrorWatch::kMinLiveFrames; f < 30; ++f) EXPECT_FALSE(live[f]) << "frame " << f;
}

// A still source whose track jumps onto its mirror and back (the tracker's heaviest mode
// changed): each jump lands where the other branch was, so the watch swaps its two filters
// and the branch the track left is live at once, every frame after the first window (before,
// each jump dropped the mirror for a window: a sure track 14-22 m off for 1 s).
TEST(MirrorWatch, ATrackThatJumpsOntoItsMirrorKeepsTheOtherBranchLive) {
  const Walk w = FindWalk();
  const Vec3 mirror = *OtherRoot(w.array, w.start_m);
  const auto flipping = [&](int f) { return (f / 12) % 2 == 0 ? w.start_m : mirror; };
  const auto live = Follow(w.array, 48, flipping);
  for (int f = MirrorWatch::kWindowFrames; f < 48; ++f) {
    ASSERT_TRUE(live[f]) << "frame " << f;
    const Vec3 other = (f / 12) % 2 == 0 ? mirror : w.start_m;
    EXPECT_LT((live[f]->position_m - other).norm(), 1e-3) << "frame " << f;
  }
}

// A still source whose track drifts off it across the line of sight for a second and then
// jumps onto the other exact solution (campaign scene 12000128: the track 2.5 m off and
// drifting, then on the other branch 7.5 m off). The frames' measured delays put the mirror
// on the source; the filter that followed the track learnt the drift and, after the swap,
// predicts the source where the drift would have taken it: its window NIS failed for 1.3 s
// and the track claimed 0.1-0.2 m while 6-7 m off. The track landed where the mirror's filter
// predicted it, so the jump is plain: the filter now following the branch the track left
// restarts at its root, and the mirror is live from the jump on.
TEST(MirrorWatch, ATrackThatDriftsAndJumpsKeepsTheBranchItLeftLive) {
  const Walk w = FindWalk();
  const Vec3 truth_m = w.start_m;
  const Vec3 ghost_m = *OtherRoot(w.array, truth_m);
  const Eigen::VectorXd sigma_s = Eigen::VectorXd::Constant(3, kSigmaS);
  constexpr int kDriftFrom = 4, kJumpAt = 14;
  constexpr double kDriftMps = 1.0;  // w.velocity_mps is a unit vector across the line of sight
  const auto track_at = [&](int f) {
    if (f >= kJumpAt) return ghost_m;
    return Vec3(truth_m + kDriftMps * w.velocity_mps * (std::max(0, f - kDriftFrom) * kHopS));
  };
  MirrorWatch watch(1.0);
  for (int f = 0; f < 30; ++f) {
    const Vec3 track_m = track_at(f);
    watch.Update(w.array, f * kHopS, track_m, TrackCovariance(w.array, track_m), w.array.Tdoa(truth_m), sigma_s,
                 kSigmaS, {});
    const std::optional<MirrorWatch::Mirror> m = watch.Live();
    if (f < kJumpAt) continue;
    ASSERT_TRUE(m) << "frame " << f;
    EXPECT_LT((m->position_m - truth_m).norm(), 1e-3) << "frame " << f;
  }
}

TEST(MirrorWatch, AMirrorOutsideTheRegionIsNeverLive) {
  const Walk w = FindWalk();
  const auto at = [&](int) { return w.start_m; };
  const Vec3 mirror = *OtherRoot(w.array, w.start_m);
  // A box around the source that leaves the mirror out (it is > 10 m away).
  MirrorWatch::Region region;
  region.bounds_min_m = w.start_m - Vec3::Constant(5.0);
  region.bounds_max_m = w.start_m + Vec3::Constant(5.0);
  ASSERT_GT((mirror - w.start_m).cwiseAbs().maxCoeff(), 5.0);
  for (const auto& live : Follow(w.array, 30, at, region)) EXPECT_FALSE(live);
  // Nor beyond the search sphere.
  MirrorWatch::Region sphere;
  sphere.radius_m = 0.5 * (mirror.norm() + w.start_m.norm());
  ASSERT_LT(w.start_m.norm(), sphere.radius_m);
  ASSERT_GT(mirror.norm(), sphere.radius_m);
  for (const auto& live : Follow(w.array, 30, at, sphere)) EXPECT_FALSE(live);
  // The same source and mirror inside both: live.
  EXPECT_TRUE(Follow(w.array, 30, at).back());
}

// A track that jumps 3 m sideways every other frame drags its mirror about faster than 1 m/s^2
// allows: the mirror never moves as a source can, so once its filter can test it, it is
// never live again.
TEST(MirrorWatch, AMirrorThatJumpsIsRuledOut) {
  const Walk w = FindWalk();
  const Vec3 side = w.start_m.cross(Vec3::UnitZ()).normalized();
  const auto jumpy = [&](int f) { return Vec3(w.start_m + (f % 2) * 3.0 * side); };
  const auto live = Follow(w.array, 40, jumpy);
  int live_frames = 0;
  for (int f = MirrorWatch::kMinLiveFrames; f < 40; ++f) live_frames += live[f].has_value();
  EXPECT_EQ(live_frames, 0);
}

// The frame's measured TDOAs, when given, place the mirror: a track on the wrong branch 3 m
// further out than the ghost still has its mirror on the source, within a few of the
// source's bound sds (the measured roots carry the noise that bound describes; the track's own
// TDOAs carry its error, which near the branch point moves their other root by metres:
// AcquisitionSession.ATrackMetresOffOnTheOtherBranchKeepsTheSourceAsItsMirror).
TEST(MirrorWatch, TheMeasuredDelaysPutTheMirrorOnTheSource) {
  const Walk w = FindWalk();
  const Vec3 truth_m = w.start_m;
  const Vec3 ghost_m = *OtherRoot(w.array, truth_m);
  const Vec3 track_m = ghost_m + 3.0 * ghost_m.normalized();
  const Eigen::VectorXd sigma_s = Eigen::VectorXd::Constant(3, kSigmaS);
  const Mat3 bound_m2 = TdoaPositionCrlb(w.array, truth_m, sigma_s);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, kSigmaS);
  MirrorWatch watch(1.0);
  for (int f = 0; f < 30; ++f) {
    Eigen::VectorXd tdoa_s = w.array.Tdoa(truth_m);
    for (Eigen::Index p = 0; p < 3; ++p) tdoa_s(p) += noise(rng);
    watch.Update(w.array, f * kHopS, track_m, 4.0 * Mat3::Identity(), tdoa_s, sigma_s, kSigmaS, {});
    if (f < MirrorWatch::kWindowFrames) continue;
    const std::optional<MirrorWatch::Mirror> m = watch.Live();
    ASSERT_TRUE(m) << "frame " << f;
    const Vec3 off_m = m->position_m - truth_m;
    EXPECT_LT(off_m.dot(bound_m2.ldlt().solve(off_m)), 25.0) << "frame " << f << ": " << off_m.norm() << " m";
  }
}

TEST(MirrorWatch, ArraysOtherThanFourSensorsAreLeftAlone) {
  const ArrayGeometry five =
      *ArrayGeometry::Create({Vec3(0, 0, 0), Vec3(20, 0, 0), Vec3(0, 20, 0), Vec3(0, 0, 20), Vec3(15, 15, 15)}, 1500.0);
  const auto at = [](int f) { return Vec3(40.0 + f * kHopS, 30.0, 10.0); };
  for (const auto& live : Follow(five, 30, at)) EXPECT_FALSE(live);
}

}  // namespace
}  // namespace localizer::engine
