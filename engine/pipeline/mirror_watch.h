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
// Each updated frame, Update takes the closed form's other exact root of the TDOAs the track
// predicts at its own mean and follows it with a constant-velocity Kalman filter (the
// particle filter's white acceleration, accel_noise_mps2), each root measured with the
// position covariance the pairs' recent delay sigmas allow there. The mirror is live while
//   * it is an exact root (residual under kExactShare of the smallest pair sigma), inside
//     the bounds and the acquisition's search sphere,
//   * it is a hypothesis of its own: more than 4 sds (track's and its own) from the track,
//   * and it moves as a source can: its filter's NIS over the last kWindowFrames frames is
//     within the chi-square 0.999 quantile (a mirror that jumps or bends faster than the
//     motion model allows, as the branches separate, fails here and is dropped until it has
//     moved plausibly for a whole window again).
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
  // One updated frame at t_s: the track's mean and position covariance, each pair's recent
  // delay sigma (s; 0 or non-finite: unknown, the fallback is used), the allowed region.
  // Arrays other than 4 sensors (3 pairs) are ignored.
  void Update(const ArrayGeometry& array, double t_s, const Vec3& track_m, const Mat3& track_cov_m2,
              const Eigen::VectorXd& pair_sigma_s, double fallback_sigma_s, const Region& region);
  // The mirror's position and covariance while it is live (above); nothing otherwise.
  struct Mirror {
    Vec3 position_m = Vec3::Zero();
    Mat3 covariance_m2 = Mat3::Zero();
  };
  std::optional<Mirror> Live() const;

 private:
  double accel_noise_mps2_;
  bool following_ = false;
  double t_s_ = 0.0;
  Vec6 mean_ = Vec6::Zero();
  Mat6 cov_ = Mat6::Zero();
  std::array<double, kWindowFrames> nis_{};
  int frames_ = 0;  // measured frames since the filter (re)started
  bool distinct_ = false;
  Mat3 last_bound_m2_ = Mat3::Zero();
  Vec3 last_root_m_ = Vec3::Zero();
};

}  // namespace localizer::engine
