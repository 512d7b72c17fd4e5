#include "engine/pipeline/mirror_watch.h"

#include <Eigen/Cholesky>
#include <cmath>
#include <numeric>
#include <vector>

#include "engine/array/multilateration.h"

namespace localizer::engine {
namespace {

// Chi-square 0.999 quantile with 3 x kWindowFrames = 24 degrees of freedom.
constexpr double kWindowNisMax = 51.18;
constexpr double kDistinctMahalanobis2 = 16.0;  // 4 sds, as the session's NearTrack
constexpr double kStartSpeedSigmaMps = 2.0;

bool Inside(const Vec3& p, const MirrorWatch::Region& region) {
  return (p.array() >= region.bounds_min_m.array()).all() && (p.array() <= region.bounds_max_m.array()).all() &&
         (p - region.centre_m).norm() <= region.radius_m;
}

}  // namespace

void MirrorWatch::Reset() {
  following_ = false;
  frames_ = 0;
  distinct_ = false;
}

void MirrorWatch::Update(const ArrayGeometry& array, double t_s, const Vec3& track_m, const Mat3& track_cov_m2,
                         const Eigen::VectorXd& pair_sigma_s, double fallback_sigma_s, const Region& region) {
  if (array.pair_count() != 3) return;
  Eigen::VectorXd sigma_s = pair_sigma_s;
  if (sigma_s.size() != 3) sigma_s = Eigen::VectorXd::Constant(3, fallback_sigma_s);
  for (Eigen::Index p = 0; p < 3; ++p) {
    if (!(sigma_s(p) > 0.0) || !std::isfinite(sigma_s(p))) sigma_s(p) = fallback_sigma_s;
  }
  if (!(sigma_s.minCoeff() > 0.0)) return;

  // The track's TDOAs and their other exact root.
  const Eigen::VectorXd tdoa_s = array.Tdoa(track_m);
  std::optional<Vec3> mirror;
  for (const Vec3& root : ClosedFormCandidates(array, tdoa_s)) {
    if (!root.allFinite()) continue;
    if ((array.Tdoa(root) - tdoa_s).cwiseAbs().maxCoeff() > kExactShare * sigma_s.minCoeff()) continue;
    if (!mirror || (root - track_m).norm() > (*mirror - track_m).norm()) mirror = root;
  }
  if (!mirror || !Inside(*mirror, region)) {
    Reset();
    return;
  }
  const Mat3 bound_m2 = TdoaPositionCrlb(array, *mirror, sigma_s);
  const Vec3 apart_m = *mirror - track_m;
  distinct_ = apart_m.dot((track_cov_m2 + bound_m2).ldlt().solve(apart_m)) > kDistinctMahalanobis2;
  last_bound_m2_ = bound_m2;
  last_root_m_ = *mirror;

  if (!following_) {
    following_ = true;
    t_s_ = t_s;
    mean_ << *mirror, Vec3::Zero();
    cov_.setZero();
    cov_.topLeftCorner<3, 3>() = bound_m2;
    cov_.bottomRightCorner<3, 3>() = kStartSpeedSigmaMps * kStartSpeedSigmaMps * Mat3::Identity();
    frames_ = 0;
    return;
  }
  // Constant velocity, white acceleration (Bar-Shalom's piecewise-constant discretisation).
  const double dt = std::max(0.0, t_s - t_s_);
  t_s_ = t_s;
  Mat6 f = Mat6::Identity();
  f.topRightCorner<3, 3>() = dt * Mat3::Identity();
  const double q = accel_noise_mps2_ * accel_noise_mps2_;
  Mat6 process = Mat6::Zero();
  process.topLeftCorner<3, 3>() = q * dt * dt * dt * dt / 4.0 * Mat3::Identity();
  process.topRightCorner<3, 3>() = process.bottomLeftCorner<3, 3>() = q * dt * dt * dt / 2.0 * Mat3::Identity();
  process.bottomRightCorner<3, 3>() = q * dt * dt * Mat3::Identity();
  mean_ = f * mean_;
  cov_ = f * cov_ * f.transpose() + process;

  const Vec3 innovation_m = *mirror - mean_.head<3>();
  const Mat3 s = cov_.topLeftCorner<3, 3>() + bound_m2;
  const Eigen::LDLT<Mat3> s_ldlt(s);
  nis_[static_cast<size_t>(frames_ % kWindowFrames)] = innovation_m.dot(s_ldlt.solve(innovation_m));
  ++frames_;
  const Eigen::Matrix<double, 6, 3> gain = cov_.leftCols<3>() * s_ldlt.solve(Mat3::Identity());
  mean_ += gain * innovation_m;
  cov_ -= gain * cov_.topRows<3>();
  cov_ = 0.5 * (cov_ + cov_.transpose());
}

std::optional<MirrorWatch::Mirror> MirrorWatch::Live() const {
  if (!following_ || !distinct_ || frames_ < kWindowFrames) return std::nullopt;
  // The window holds the last kWindowFrames NIS values once frames_ >= kWindowFrames.
  const double window_nis = std::accumulate(nis_.begin(), nis_.end(), 0.0);
  if (!(window_nis <= kWindowNisMax)) return std::nullopt;
  return Mirror{last_root_m_, last_bound_m2_};
}

}  // namespace localizer::engine
