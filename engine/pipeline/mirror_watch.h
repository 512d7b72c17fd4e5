// The other exact solution of a 4-sensor array's three TDOAs (the track's "mirror"),
// followed beside the track so that the estimate says when the data allow it.
//
// Three TDOAs fix a position only up to two exact solutions (multilateration.h): wherever a
// track sits, its mirror explains every frame just as well, and only the motion can tell the
// two apart. A track that started on the wrong one, or took the wrong branch where the two
// met, is then wrong by metres while every innovation is small (campaign scene 2000127:
// 3-11 m off for 6 s at NIS ~1 claiming 2-20 cm). The particle filter resolves the pair when
// it holds both from a start; this watch covers the rest.
//
// Each updated frame, Update takes the other exact root of the frame's measured TDOAs when it
// is given them (the update used all three pairs): of the exact roots more than 4 sds from the
// track, the one nearest (in metres) where the mirror's filter predicts it, or at a start the
// one farther from the track. Else, or when no measured root qualifies, it takes the other
// exact root of the TDOAs the track predicts at its own mean. The measured roots carry the
// pairs' noise, which the mirror's bound below describes; the track's predicted TDOAs carry
// its own error, which near the branch point moves their other root by metres (campaign scene
// 33000075: 2.5 m from the source, so the mirror was dropped as no longer distinct from a
// track 5.5 m off). But pairs on echoes or a fast source make the measured root jump
// (27000182), so a session runs one watch of each kind and reports whichever is live
// (session_impl.h). The root is followed with a constant-velocity Kalman filter (the
// particle filter's white acceleration, accel_noise_mps2), each root measured with the
// position covariance the pairs' recent delay sigmas allow there. A second such filter
// follows the track's own mean. When the track jumps onto its mirror's branch (the tracker's
// heaviest mode changed, or its particles crossed over where the branches met), the new root
// is where the track was going and the track is where the mirror was going: the two filters
// swap, so that the old track, which has moved as a source can, is the mirror from that frame
// on (before, the mirror was dropped for a window after each jump: campaign scenes 3000099
// and 9000031 then claimed 1 s of a sure position 14-22 m off). Where the track left where
// its filter predicted it (the kept pairing's squared distance above the chi-square 0.999
// quantile for 6 degrees of freedom: not a near tie between branches that run close, as
// inside a small array) and landed where the mirror's filter predicted it (0.999, 3), the
// jump is plain and the filter now on the branch the track left restarts at that branch's
// root, live at once: it had followed the track, and a track drifting off the source before
// it jumped taught it the drift, so it predicted the source metres away and failed the window
// test for a second and more (campaign scene 12000128: 1.3 s claiming 0.1-0.2 m 6-7 m off).
// The mirror is live while
//   * it is an exact root (residual under kExactShare of the smallest pair sigma), inside
//     the bounds and the acquisition's search sphere,
//   * it is a hypothesis of its own: more than 4 sds (track's and its own) from the track,
//   * and nothing has ruled it out: only motion tells a source from its mirror, so the
//     mirror of a track that has just (re)started counts until its filter can test it
//     (kMinLiveFrames updates: two give it a velocity, a third tests it), and from then on
//     while their NIS, over the last kWindowFrames at most, is within the chi-square 0.999
//     quantile for that many frames (a mirror that jumps or bends faster than the motion
//     model allows, as the branches separate, fails here and is dropped until it has moved
//     plausibly for a whole window again). Before, a mirror counted only once it had passed:
//     a new or restarted filter then left the track alone for its first frames, where the
//     track is as likely on the wrong branch as on the right one (campaign scene 28000102:
//     three frames just after its start claimed 0.03-0.36 m while 1.3-2.7 m off; PHAT draws
//     1-30, summed silent time 14.8 -> 13.3 s, down in six scenes, up in none: ACCURACY.md,
//     "Forty-first pass").
// Where the root becomes a hypothesis of its own (it was within the track's spread, as near
// the branch point) while its filter fails that test, the filter restarts at the root: what it
// learnt from a root that jumped about the branch point says nothing of how the mirror moves
// now, and kept, it held the source uncovered for a whole window (campaign scene 28000102:
// 1.0-1.8 m off claiming 0.1-0.3 m for 0.7 s). A filter that passes keeps its history. The
// restarted filter counts until it is tested, as a new one does, unless the branches parted
// within the last kWindowFrames frames before: a root that keeps parting from the track and
// closing on it again would otherwise be restarted, and counted, for ever.
// The session then reports the estimate ambiguous with a covariance that covers the mirror
// (session_tracking.cc, Report). Reporting only: the track is not changed.
// Cost: one closed form, one 3x3 bound and a 6-state Kalman step per frame, 4-sensor arrays only.
#pragma once

#include <Eigen/Core>
#include <array>
#include <optional>

#include "engine/array/array_geometry.h"
#include "engine/core/types.h"

namespace localizer::engine {

class MirrorWatch {
 public:
  static constexpr int kWindowFrames = 8;
  // Two updates give the mirror's filter a velocity; a third tests it.
  static constexpr int kMinLiveFrames = 3;
  static constexpr double kExactShare = 0.1;

  struct Region {
    Vec3 bounds_min_m = Vec3::Constant(-1e300);
    Vec3 bounds_max_m = Vec3::Constant(1e300);
    Vec3 centre_m = Vec3::Zero();
    double radius_m = 1e300;
  };

  explicit MirrorWatch(double accel_noise_mps2) : accel_noise_mps2_(accel_noise_mps2) {}

  // Forgets the mirror (a restart, a dropped track).
  void Reset();
  // Update follows the mirror of whatever track it is given. A session whose tracker holds
  // several hypotheses gives it the heaviest one's, so that the mirror has been seen moving
  // by the time the tracker keeps one hypothesis.
  // One updated frame at t_s: the track's mean and position covariance, the frame's three
  // measured delays when the update used all three (else empty), each pair's recent delay
  // sigma (s; 0 or non-finite: unknown, the fallback is used), the TDOA noise the track's
  // filter assumes (fallback_sigma_s, s: also a floor on the noise of the mirror's root, which
  // scatters with the errors the filter sees), the allowed region. Arrays other than 4
  // sensors (3 pairs) are ignored.
  void Update(const ArrayGeometry& array, double t_s, const Vec3& track_m, const Mat3& track_cov_m2,
              const Eigen::VectorXd& measured_tdoa_s, const Eigen::VectorXd& pair_sigma_s, double fallback_sigma_s,
              const Region& region);
  // The mirror's position and covariance while it is live (above: distinct, inside the
  // region, not ruled out); nothing otherwise.
  struct Mirror {
    Vec3 position_m = Vec3::Zero();
    Mat3 covariance_m2 = Mat3::Zero();
  };
  std::optional<Mirror> Live() const;

 private:
  // A constant-velocity Kalman filter on one branch's positions, with its recent NIS.
  struct Follower {
    bool following = false;
    double t_s = 0.0;
    Vec6 mean = Vec6::Zero();
    Mat6 cov = Mat6::Zero();
    std::array<double, kWindowFrames> nis{};
    int frames = 0;  // measured frames since the filter (re)started
    // Counts before it is tested: a watch's first follower does (nothing has told the branches
    // apart yet), and one restarted because the branches parted, unless they last parted
    // within kWindowFrames frames (a root that keeps parting from the track and closing on it
    // again would otherwise be restarted, and counted, for ever).
    bool presumed = false;

    void Start(double at_t_s, const Vec3& at_m, const Mat3& noise_m2, bool presumed_live);
    void Predict(double to_t_s, double accel_noise_mps2);
    // Squared Mahalanobis distance of a measurement from the prediction.
    double Distance2(const Vec3& at_m, const Mat3& noise_m2) const;
    void Update(const Vec3& at_m, const Mat3& noise_m2);  // records the NIS
    // At least kMinLiveFrames updates since the (re)start, and the NIS of the last
    // min(frames, kWindowFrames) within their chi-square 0.999 quantile.
    bool MovedAsASourceCan() const;
    // Whether the branch counts as a hypothesis: untested (fewer than kMinLiveFrames
    // updates), as `presumed` says; tested, MovedAsASourceCan.
    bool Counts() const { return frames < kMinLiveFrames ? presumed : MovedAsASourceCan(); }
  };

  double accel_noise_mps2_;
  Follower mirror_;
  Follower track_;
  bool distinct_ = false;
  // Updates since the mirror's filter last restarted where the branches parted (capped).
  int frames_since_parting_ = kWindowFrames;
  Mat3 last_noise_m2_ = Mat3::Zero();
  Vec3 last_root_m_ = Vec3::Zero();
};

}  // namespace localizer::engine
