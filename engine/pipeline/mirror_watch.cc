#include "engine/pipeline/mirror_watch.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <utility>
#include <vector>

#include "engine/array/multilateration.h"

namespace localizer::engine {
namespace {

// Chi-square 0.999 quantiles with 3 n degrees of freedom, n = 0 ... kWindowFrames frames.
constexpr std::array<double, MirrorWatch::kWindowFrames + 1> kWindowNisMax = {0.0,   16.27, 22.46, 27.88, 32.91,
                                                                              37.70, 42.31, 46.80, 51.18};
constexpr double kDistinctMahalanobis2 = 16.0;  // 4 sds, as the session's NearTrack
// Chi-square 0.999 quantiles: the track landed where the mirror's filter predicted it (3
// degrees of freedom); the kept pairing of root and track is implausible (6).
constexpr double kLandedMahalanobis2 = 16.27;
constexpr double kJumpMahalanobis2 = 22.46;
constexpr double kStartSpeedSigmaMps = 2.0;

bool Inside(const Vec3& p, const MirrorWatch::Region& region) {
  return (p.array() >= region.bounds_min_m.array()).all() && (p.array() <= region.bounds_max_m.array()).all() &&
         (p - region.centre_m).norm() <= region.radius_m;
}

}  // namespace

void MirrorWatch::Reset() {
  mirror_ = Follower{};
  track_ = Follower{};
  distinct_ = false;
  frames_since_parting_ = kWindowFrames;
}

void MirrorWatch::Follower::Start(double at_t_s, const Vec3& at_m, const Mat3& noise_m2, bool presumed_live) {
  following = true;
  presumed = presumed_live;
  t_s = at_t_s;
  mean << at_m, Vec3::Zero();
  cov.setZero();
  cov.topLeftCorner<3, 3>() = noise_m2;
  cov.bottomRightCorner<3, 3>() = kStartSpeedSigmaMps * kStartSpeedSigmaMps * Mat3::Identity();
  frames = 0;
  nis.fill(0.0);
}

void MirrorWatch::Follower::Predict(double to_t_s, double accel_noise_mps2) {
  // Constant velocity, white acceleration (Bar-Shalom's piecewise-constant discretisation).
  const double dt = std::max(0.0, to_t_s - t_s);
  t_s = to_t_s;
  Mat6 f = Mat6::Identity();
  f.topRightCorner<3, 3>() = dt * Mat3::Identity();
  const double q = accel_noise_mps2 * accel_noise_mps2;
  Mat6 process = Mat6::Zero();
  process.topLeftCorner<3, 3>() = q * dt * dt * dt * dt / 4.0 * Mat3::Identity();
  process.topRightCorner<3, 3>() = process.bottomLeftCorner<3, 3>() = q * dt * dt * dt / 2.0 * Mat3::Identity();
  process.bottomRightCorner<3, 3>() = q * dt * dt * Mat3::Identity();
  mean = f * mean;
  cov = f * cov * f.transpose() + process;
}

bool MirrorWatch::Follower::MovedAsASourceCan() const {
  if (frames < kMinLiveFrames) return false;
  // The window holds the last min(frames, kWindowFrames) NIS values (the others are 0).
  const int n = std::min(frames, kWindowFrames);
  const double window_nis = std::accumulate(nis.begin(), nis.end(), 0.0);
  return window_nis <= kWindowNisMax[static_cast<size_t>(n)];
}

double MirrorWatch::Follower::Distance2(const Vec3& at_m, const Mat3& noise_m2) const {
  const Vec3 innovation_m = at_m - mean.head<3>();
  return innovation_m.dot((cov.topLeftCorner<3, 3>() + noise_m2).ldlt().solve(innovation_m));
}

void MirrorWatch::Follower::Update(const Vec3& at_m, const Mat3& noise_m2) {
  const Vec3 innovation_m = at_m - mean.head<3>();
  const Eigen::LDLT<Mat3> s_ldlt(cov.topLeftCorner<3, 3>() + noise_m2);
  nis[static_cast<size_t>(frames % kWindowFrames)] = innovation_m.dot(s_ldlt.solve(innovation_m));
  ++frames;
  const Eigen::Matrix<double, 6, 3> gain = cov.leftCols<3>() * s_ldlt.solve(Mat3::Identity());
  mean += gain * innovation_m;
  cov -= gain * cov.topRows<3>();
  cov = 0.5 * (cov + cov.transpose());
}

void MirrorWatch::Update(const ArrayGeometry& array, double t_s, const Vec3& track_m, const Mat3& track_cov_m2,
                         const Eigen::VectorXd& measured_tdoa_s, const Eigen::VectorXd& pair_sigma_s,
                         double fallback_sigma_s, const Region& region) {
  if (array.pair_count() != 3) return;
  Eigen::VectorXd sigma_s = pair_sigma_s;
  if (sigma_s.size() != 3) sigma_s = Eigen::VectorXd::Constant(3, fallback_sigma_s);
  for (Eigen::Index p = 0; p < 3; ++p) {
    if (!(sigma_s(p) > 0.0) || !std::isfinite(sigma_s(p))) sigma_s(p) = fallback_sigma_s;
  }
  if (!(sigma_s.minCoeff() > 0.0)) return;

  // The other exact root: of the measured TDOAs when given, else of the track's (the header
  // says which and why).
  const auto exact_roots = [&](const Eigen::VectorXd& tdoa_s) {
    std::vector<Vec3> out;
    for (const Vec3& root : ClosedFormCandidates(array, tdoa_s)) {
      if (!root.allFinite()) continue;
      if ((array.Tdoa(root) - tdoa_s).cwiseAbs().maxCoeff() > kExactShare * sigma_s.minCoeff()) continue;
      out.push_back(root);
    }
    return out;
  };
  const auto farthest_from_track = [&](const std::vector<Vec3>& roots) {
    std::optional<Vec3> out;
    for (const Vec3& root : roots) {
      if (!out || (root - track_m).norm() > (*out - track_m).norm()) out = root;
    }
    return out;
  };
  std::optional<Vec3> mirror;
  if (measured_tdoa_s.size() == 3 && measured_tdoa_s.allFinite()) {
    // The measured roots apart from the track's own (within 4 sds of it).
    std::vector<Vec3> roots;
    for (const Vec3& root : exact_roots(measured_tdoa_s)) {
      const Vec3 apart_m = root - track_m;
      const Mat3 both_m2 = track_cov_m2 + TdoaPositionCrlb(array, root, sigma_s);
      if (apart_m.dot(both_m2.ldlt().solve(apart_m)) > kDistinctMahalanobis2) roots.push_back(root);
    }
    if (mirror_.following && track_.following && !roots.empty()) {
      // Nearest in metres: a root's own bound grows without limit far out, so a Mahalanobis
      // distance would favour a root a kilometre away.
      Follower predicted = mirror_;
      predicted.Predict(t_s, accel_noise_mps2_);
      double best_m = std::numeric_limits<double>::infinity();
      for (const Vec3& root : roots) {
        const double d_m = (root - predicted.mean.head<3>()).norm();
        if (d_m < best_m) {
          best_m = d_m;
          mirror = root;
        }
      }
    } else {
      mirror = farthest_from_track(roots);
    }
  }
  if (!mirror) mirror = farthest_from_track(exact_roots(array.Tdoa(track_m)));
  if (!mirror || !Inside(*mirror, region)) {
    Reset();
    return;
  }
  const Mat3 bound_m2 = TdoaPositionCrlb(array, *mirror, sigma_s);
  // The root scatters with the TDOA errors the track's filter sees, which can be far above the
  // pairs' own delay sigmas (impulses, low SNR: campaign scene 22000120, a root jumping by a
  // metre against a 0.15 m bound). The follower and the reported mirror use the larger; the
  // distinctness test keeps the pairs' bound.
  Eigen::VectorXd seen_sigma_s = sigma_s;
  for (Eigen::Index p = 0; p < seen_sigma_s.size(); ++p) seen_sigma_s(p) = std::max(seen_sigma_s(p), fallback_sigma_s);
  const Mat3 noise_m2 = TdoaPositionCrlb(array, *mirror, seen_sigma_s);
  const Vec3 apart_m = *mirror - track_m;
  const bool was_distinct = distinct_;
  distinct_ = apart_m.dot((track_cov_m2 + bound_m2).ldlt().solve(apart_m)) > kDistinctMahalanobis2;
  last_noise_m2_ = noise_m2;
  last_root_m_ = *mirror;

  if (!mirror_.following || !track_.following) {
    mirror_.Start(t_s, *mirror, noise_m2, true);
    track_.Start(t_s, track_m, track_cov_m2, true);
    return;
  }
  frames_since_parting_ = std::min(frames_since_parting_ + 1, kWindowFrames);
  if (distinct_ && !was_distinct && !mirror_.MovedAsASourceCan()) {
    // The branches have just parted, and the mirror's filter failed its window while its root
    // was within the track's own uncertainty (near the branch point, where the roots move
    // fastest and bend): that history says nothing of how the mirror moves now.
    mirror_.Start(t_s, *mirror, noise_m2, frames_since_parting_ >= kWindowFrames);
    frames_since_parting_ = 0;
    track_.Predict(t_s, accel_noise_mps2_);
    track_.Update(track_m, track_cov_m2);
    return;
  }
  mirror_.Predict(t_s, accel_noise_mps2_);
  track_.Predict(t_s, accel_noise_mps2_);
  // The track jumped onto the mirror's branch: each filter now follows the other branch.
  // landed2: how far the track is from where the mirror's filter predicted it.
  const double landed2 = mirror_.Distance2(track_m, track_cov_m2);
  const double kept2 = mirror_.Distance2(*mirror, noise_m2) + track_.Distance2(track_m, track_cov_m2);
  const double swapped2 = track_.Distance2(*mirror, noise_m2) + landed2;
  if (swapped2 < kept2) {
    // A plain jump: the track left where its own filter predicted it (the kept pairing is
    // implausible, not a near tie between branches that run close) and landed where the
    // mirror's filter predicted it (before the swap).
    const bool plain_jump = kept2 > kJumpMahalanobis2 && landed2 <= kLandedMahalanobis2;
    std::swap(mirror_, track_);
    if (plain_jump) {
      // The filter now on the branch the track left had learnt the track's motion (a drift,
      // say), not the branch's: it restarts at the root, live at once (the header says why).
      mirror_.Start(t_s, *mirror, noise_m2, true);
      mirror_.frames = kWindowFrames;  // a window of zero NIS (Start cleared it): passes at once
      track_.Update(track_m, track_cov_m2);
      return;
    }
  }
  mirror_.Update(*mirror, noise_m2);
  track_.Update(track_m, track_cov_m2);
}

std::optional<MirrorWatch::Mirror> MirrorWatch::Live() const {
  if (!mirror_.following || !distinct_ || !mirror_.Counts()) return std::nullopt;
  return Mirror{last_root_m_, last_noise_m2_};
}

}  // namespace localizer::engine
