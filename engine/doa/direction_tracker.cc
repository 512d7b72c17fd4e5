#include "engine/doa/direction_tracker.h"

#include <cmath>

namespace localizer::engine {
namespace {
constexpr double kRadialShare = 0.1;  // the radial sigma, as a share of the tangential one
constexpr double kMaxSigmaRad = 0.5;  // a track more uncertain than this is deleted
}  // namespace

Status DirectionTrackerOptions::Validate() const {
  if (!(peak_sigma_rad > 0.0) || peak_sigma_rad > 1.0) return InvalidArgument("peak_sigma_rad must be in (0, 1]");
  if (!(angular_accel_noise_radps2 > 0.0) || !std::isfinite(angular_accel_noise_radps2))
    return InvalidArgument("angular_accel_noise_radps2 must be positive");
  if (!(max_coast_s > 0.0) || !(frame_period_s > 0.0) || max_coast_s / frame_period_s > 1e6)
    return InvalidArgument("max_coast_s and frame_period_s must be positive (and their ratio at most 1e6)");
  if (!(initial_rate_sigma_radps > 0.0) || !std::isfinite(initial_rate_sigma_radps))
    return InvalidArgument("initial_rate_sigma_radps must be positive");
  return Status::Ok();  // confirm_hits / confirm_window: TwsOptions::Validate names them
}

StatusOr<DirectionTracker> DirectionTracker::Create(ArrayShape shape, const DirectionTrackerOptions& options) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  tws::TwsOptions tws;
  tws.dimensions = shape == ArrayShape::kLinear ? 2 : 3;
  tws.accel_noise_mps2 = options.angular_accel_noise_radps2;
  tws.confirm_hits = options.confirm_hits;
  tws.confirm_window = options.confirm_window;
  tws.max_coast_scans = static_cast<int>(std::ceil(options.max_coast_s / options.frame_period_s));
  tws.max_position_sigma_m = kMaxSigmaRad;
  tws.initial_speed_sigma_mps = options.initial_rate_sigma_radps;
  tws.max_tracks = 64;
  auto tracker = tws::TwsTracker::Create(tws);
  if (!tracker.ok()) return tracker.status();
  return DirectionTracker(shape, options, std::move(*tracker));
}

Status DirectionTracker::Update(double t_s, const std::vector<DirectionPeak>& peaks, std::vector<SourceTrack>* out,
                                bool include_tentative) {
  const bool linear = shape_ == ArrayShape::kLinear;
  const double s2 = options_.peak_sigma_rad * options_.peak_sigma_rad;
  plots_.clear();
  for (const DirectionPeak& peak : peaks) {
    const Vec3 u = linear ? Vec3(std::cos(peak.cone_angle_rad), std::sin(peak.cone_angle_rad), 0.0) : peak.direction;
    if (!u.allFinite()) return InvalidArgument("a peak without a direction for this array's shape");
    tws::CartesianPlot plot;
    plot.position_m = u;
    const Mat3 radial = u * u.transpose();
    plot.covariance_m2 = s2 * (Mat3::Identity() - radial) + kRadialShare * kRadialShare * s2 * radial;
    if (linear) plot.covariance_m2(2, 2) = s2;  // unused by a 2-D tracker; keeps it definite
    plots_.push_back(plot);
  }
  LOCALIZER_RETURN_IF_ERROR(tracker_->ProcessCartesian(t_s, plots_));
  tracker_->Tracks(&reports_, include_tentative);
  out->clear();
  for (const tws::TrackReport& r : reports_) {
    SourceTrack track;
    track.id = r.id;
    track.status = r.status;
    const Vec3 p = r.position_m;
    const double norm = p.norm();
    if (!(norm > 0.0)) continue;
    const Vec3 u = p / norm;
    // The angular spread: the position covariance across the direction, over the radius.
    const Mat3 across = Mat3::Identity() - u * u.transpose();
    track.sigma_rad = std::sqrt(std::max(0.0, (across * r.covariance.topLeftCorner<3, 3>() * across).trace())) / norm;
    if (linear) {
      track.cone_angle_rad = std::atan2(std::abs(u.y()), u.x());
    } else {
      track.direction = u;
      track.azimuth_rad = std::atan2(u.y(), u.x());
      track.elevation_rad = std::asin(std::clamp(u.z(), -1.0, 1.0));
    }
    out->push_back(track);
  }
  return Status::Ok();
}

}  // namespace localizer::engine
