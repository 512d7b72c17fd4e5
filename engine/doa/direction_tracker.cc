#include "engine/doa/direction_tracker.h"

#include <algorithm>
#include <cmath>

namespace localizer::engine {
namespace {
constexpr double kRadialShare = 0.1;  // the radial sigma, as a share of the tangential one
constexpr double kMaxSigmaRad = 0.5;  // a track more uncertain than this is deleted
// Two directions are one source's when SameSourceD2 is below this: the chi^2_3 quantile at
// 0.9995, the tracker's gate (tws_options.h), so within about 4.2 x sqrt(2) peak sigmas.
constexpr double kSameSourceGate = 17.73;
}  // namespace

Status DirectionTrackerOptions::Validate() const {
  if (!(peak_sigma_rad > 0.0) || peak_sigma_rad > 1.0) return InvalidArgument("peak_sigma_rad must be in (0, 1]");
  if (!(angular_accel_noise_radps2 > 0.0) || !std::isfinite(angular_accel_noise_radps2))
    return InvalidArgument("angular_accel_noise_radps2 must be positive");
  if (!(max_coast_s > 0.0) || !(frame_period_s > 0.0) || max_coast_s / frame_period_s > 1e6)
    return InvalidArgument("max_coast_s and frame_period_s must be positive (and their ratio at most 1e6)");
  if (!(initial_rate_sigma_radps > 0.0) || !std::isfinite(initial_rate_sigma_radps))
    return InvalidArgument("initial_rate_sigma_radps must be positive");
  if (!(max_elevation_sigma_rad >= peak_sigma_rad) || max_elevation_sigma_rad > 1.0)
    return InvalidArgument("max_elevation_sigma_rad must be in [peak_sigma_rad, 1]");
  if (!(echo_window_s >= 0.0) || !std::isfinite(echo_window_s)) return InvalidArgument("echo_window_s must be >= 0");
  if (!(resume_after_s >= 0.0) || resume_after_s / frame_period_s > 1e6)
    return InvalidArgument("resume_after_s must be >= 0 (and at most 1e6 frames)");
  if (!(lost_source_after_s >= 0.0) || !std::isfinite(lost_source_after_s))
    return InvalidArgument("lost_source_after_s must be >= 0");
  if (steady_hits < 1) return InvalidArgument("steady_hits must be >= 1");
  if (min_lead_frames < 0) return InvalidArgument("min_lead_frames must be >= 0");
  if (!(remember_identity_s >= 0.0) || !std::isfinite(remember_identity_s))
    return InvalidArgument("remember_identity_s must be finite and >= 0");
  if (!(min_lead_share >= 0.0 && min_lead_share <= 1.0)) return InvalidArgument("min_lead_share must be in [0, 1]");
  if (persistent_leader_frames < 0) return InvalidArgument("persistent_leader_frames must be >= 0");
  if (!(co_lead_share >= 0.0 && co_lead_share <= 1.0)) return InvalidArgument("co_lead_share must be in [0, 1]");
  if (!(coast_rate_decay_s >= 0.0) || !std::isfinite(coast_rate_decay_s))
    return InvalidArgument("coast_rate_decay_s must be finite and >= 0");
  return Status::Ok();  // confirm_hits / confirm_window: TwsOptions::Validate names them
}

StatusOr<DirectionTracker> DirectionTracker::Create(const ArrayShapeInfo& shape,
                                                    const DirectionTrackerOptions& options) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  if (shape.shape == ArrayShape::kPlanar && !(std::abs(shape.axis.norm() - 1.0) < 1e-6))
    return InvalidArgument("a planar array's shape needs its unit normal in axis");
  tws::TwsOptions tws;
  tws.dimensions = shape.shape == ArrayShape::kLinear ? 2 : 3;
  tws.accel_noise_mps2 = options.angular_accel_noise_radps2;
  tws.confirm_hits = options.confirm_hits;
  tws.confirm_window = options.confirm_window;
  tws.max_coast_scans = static_cast<int>(std::ceil(options.max_coast_s / options.frame_period_s));
  tws.max_position_sigma_m = kMaxSigmaRad;
  tws.initial_speed_sigma_mps = options.initial_rate_sigma_radps;
  tws.max_tracks = 64;
  tws.coast_velocity_decay_s = options.coast_rate_decay_s;
  if (options.start_at_onsets_only) tws.max_initiations_per_scan = 1;
  if (options.resume_after_s > 0.0)
    tws.resume_misses = std::max(1, static_cast<int>(std::ceil(options.resume_after_s / options.frame_period_s)));
  auto tracker = tws::TwsTracker::Create(tws);
  if (!tracker.ok()) return tracker.status();
  OnsetOptions onset;
  onset.min_rise_db = options.onset_min_rise_db;
  onset.memory_s = options.onset_memory_s;
  onset.frame_period_s = options.frame_period_s;
  auto detector = OnsetDetector::Create(onset);
  if (!detector.ok()) return InvalidArgument("onset_" + detector.status().message());
  return DirectionTracker(shape, options, std::move(*tracker), std::move(*detector));
}

Mat3 DirectionTracker::PeakCovariance(const Vec3& u) const {
  const double s2 = options_.peak_sigma_rad * options_.peak_sigma_rad;
  const Mat3 radial = u * u.transpose();
  const Mat3 radial_part = kRadialShare * kRadialShare * s2 * radial;
  if (shape_.shape != ArrayShape::kPlanar) return s2 * (Mat3::Identity() - radial) + radial_part;
  const Vec3& n = shape_.axis;
  const double z = u.dot(n);
  const Vec3 in_plane = u - z * n;
  // The sign of z follows the hemisphere the peak was reported on; its size is floored.
  const double floor = options_.peak_sigma_rad / options_.max_elevation_sigma_rad;
  const double z_eff = std::copysign(std::max(std::abs(z), floor), z == 0.0 ? 1.0 : z);
  const Mat3 step = Mat3::Identity() - n * in_plane.transpose() / z_eff;
  const Mat3 plane = Mat3::Identity() - n * n.transpose();
  return s2 * step * plane * step.transpose() + radial_part;
}

bool DirectionTracker::Persists(PeakRun* run, const Vec3& u) const {
  const bool same = run->frames > 0 && SameSourceD2(run->u, u) < kSameSourceGate;
  run->frames = !u.allFinite() ? 0 : same ? run->frames + 1 : 1;
  run->u = u;
  return options_.persistent_leader_frames > 0 && run->frames >= options_.persistent_leader_frames;
}

bool DirectionTracker::NoTrackNear(const Vec3& u) const {
  return std::none_of(reports_.begin(), reports_.end(), [&](const tws::TrackReport& r) {
    return r.position_m.norm() > 0.0 && SameSourceD2(r.position_m.normalized(), u) < 4.0 * kSameSourceGate;
  });
}

double DirectionTracker::SameSourceD2(const Vec3& a, const Vec3& b) const {
  Vec3 pa = a, pb = b;
  // A planar array compares azimuths: near its plane it sees elevation through cos(elevation),
  // and a room's peaks scatter by 5-15 degrees in elevation (PeakCovariance). The 3-D
  // Mahalanobis distance with that covariance was tried: its nearly exact radial part made
  // any elevation difference of ten degrees or more a different source.
  if (shape_.shape == ArrayShape::kPlanar) {
    pa -= pa.dot(shape_.axis) * shape_.axis;
    pb -= pb.dot(shape_.axis) * shape_.axis;
  }
  if (!(pa.norm() > 0.0) || !(pb.norm() > 0.0)) return 1e300;
  const double angle = std::acos(std::clamp(pa.normalized().dot(pb.normalized()), -1.0, 1.0));
  return angle * angle / (2.0 * options_.peak_sigma_rad * options_.peak_sigma_rad);
}

Vec3 DirectionTracker::UnitOf(const DirectionPeak& peak) const {
  if (shape_.shape != ArrayShape::kLinear) return peak.direction;
  return Vec3(std::cos(peak.cone_angle_rad), std::sin(peak.cone_angle_rad), 0.0);
}

bool DirectionTracker::Leads(const Lineage& l) const {
  return l.leads >= options_.min_lead_frames && l.leads >= options_.min_lead_share * l.hits;
}

void DirectionTracker::UpdateLineages(double t_s, const DirectionPeak* riser) {
  for (auto it = lineage_.begin(); it != lineage_.end();) {  // forget the deleted tracks
    const uint64_t id = it->first;
    const bool alive =
        std::any_of(reports_.begin(), reports_.end(), [&](const tws::TrackReport& r) { return r.id == id; });
    // A deleted track whose source was reported: its identity is remembered ("Identities").
    const Lineage& l = it->second;
    if (!alive && options_.remember_identity_s > 0.0 && l.confirmed && l.anchor.allFinite() && Leads(l))
      departed_.push_back({l, t_s + options_.remember_identity_s});
    it = alive ? std::next(it) : lineage_.erase(it);
  }
  departed_.erase(
      std::remove_if(departed_.begin(), departed_.end(), [&](const Departed& d) { return d.until_s < t_s; }),
      departed_.end());
  const Vec3 riser_u = riser ? UnitOf(*riser) : Vec3::Zero();
  uint64_t riser_track = 0;
  double riser_d2 = kSameSourceGate;
  // The tracks that led: for the frame's strongest peak (plots_ keep the peaks' order:
  // strongest first) and each peak of at least co_lead_share of its statistic, the hit track
  // nearest it.
  std::vector<uint64_t>& leaders = leaders_;
  leaders.assign(plots_.size(), 0);
  std::vector<double>& leader_d2 = leader_d2_;
  leader_d2.assign(plots_.size(), kSameSourceGate);
  for (const tws::TrackReport& r : reports_) {
    Lineage& l = lineage_[r.id];
    const bool born = l.reported_id == 0;
    if (born) l.reported_id = r.id;
    const bool hit = r.consecutive_misses == 0;
    l.run = hit ? l.run + 1 : 0;
    l.hits += hit;
    l.hit_bits = (l.hit_bits << 1) | static_cast<uint32_t>(hit);
    l.led = false;
    if (!(r.position_m.norm() > 0.0)) continue;
    const Vec3 u = r.position_m.normalized();
    if (born || l.run >= options_.steady_hits) l.anchor = u, l.anchor_s = t_s;
    if (riser && hit) {  // the track that heard the frame's rising peak: its source (re)started there
      const double d2 = SameSourceD2(u, riser_u);
      if (d2 < riser_d2) riser_d2 = d2, riser_track = r.id;
    }
    for (size_t k = 0; hit && k < plots_.size(); ++k) {
      if (k > 0 && !(options_.co_lead_share > 0.0 && plot_share_[k] >= options_.co_lead_share)) continue;
      const double d2 = SameSourceD2(u, plots_[k].position_m);
      if (d2 < leader_d2[k]) leader_d2[k] = d2, leaders[k] = r.id;
    }
  }
  if (riser_track != 0) lineage_[riser_track].anchor = riser_u, lineage_[riser_track].anchor_s = t_s;
  std::sort(leaders.begin(), leaders.end());
  leaders.erase(std::unique(leaders.begin(), leaders.end()), leaders.end());
  for (uint64_t id : leaders) {
    if (id == 0) continue;
    ++lineage_[id].leads;
    lineage_[id].led = true;
  }
  // A track confirmed now, where another's source was last heard, is that source resuming:
  // it joins that track's identity.
  for (const tws::TrackReport& r : reports_) {
    Lineage& l = lineage_[r.id];
    if (r.status == tws::TrackStatus::kTentative || l.confirmed) continue;
    l.confirmed = true;
    if (!options_.continue_identities || !(r.position_m.norm() > 0.0)) continue;
    const Vec3 u = r.position_m.normalized();
    const Lineage* best = nullptr;
    double best_d2 = kSameSourceGate;
    for (const tws::TrackReport& o : reports_) {
      const Lineage& lo = lineage_[o.id];
      if (o.id == r.id || !lo.confirmed || !lo.anchor.allFinite()) continue;
      const double d2 = SameSourceD2(lo.anchor, u);
      if (d2 < best_d2) best_d2 = d2, best = &lo;
    }
    const Departed* gone = nullptr;  // or a deleted one's, remembered
    for (const Departed& d : departed_) {
      const double d2 = SameSourceD2(d.lineage.anchor, u);
      if (d2 < best_d2) best_d2 = d2, best = &d.lineage, gone = &d;
    }
    if (!best) continue;
    l.reported_id = best->reported_id;
    // The same source: its record of leading carries over.
    if (best->leads > l.leads) l.leads = best->leads, l.hits = best->hits;
    if (gone) departed_.erase(departed_.begin() + (gone - departed_.data()));  // its identity is taken
  }
  // One track speaks for each identity: the one whose source was heard last (the newer on a
  // tie).
  for (auto& [id, l] : lineage_) {
    l.shown = true;
    for (const auto& [other, lo] : lineage_) {
      if (other == id || lo.reported_id != l.reported_id) continue;
      if (lo.anchor_s > l.anchor_s || (lo.anchor_s == l.anchor_s && other > id)) l.shown = false;
    }
  }
}

Status DirectionTracker::Update(double t_s, const std::vector<DirectionPeak>& peaks, double band_power,
                                std::vector<SourceTrack>* out, bool include_tentative) {
  LOCALIZER_RETURN_IF_ERROR(onset_.Push(band_power));
  // Not on a frame whose power fell (an offset): there the direct sound stops first and
  // the reflections linger, so they rise relative to it.
  const bool may_start = onset_.onset();
  const bool linear = shape_.shape == ArrayShape::kLinear;
  const double s2 = options_.peak_sigma_rad * options_.peak_sigma_rad;
  // Precedence: the peak that rose most is where the onset's source is; the others are
  // earlier sources or reflections of the new one.
  const DirectionPeak* riser = nullptr;
  for (const DirectionPeak& peak : peaks)
    if (!riser || peak.rise > riser->rise) riser = &peak;
  // Echo suppression: for echo_window_s after a direction rose past the threshold, the
  // reflections of that source build up and rise too; only a peak at least as strong as the
  // one that rose may start a track then (a second source, not an image: images are weaker).
  bool echo_blocks = false;
  if (riser && riser->rise >= riser->threshold) {
    const bool open = t_s <= echo_until_s_;
    echo_blocks = open && riser->statistic < echo_statistic_;
    echo_statistic_ = open ? std::max(echo_statistic_, riser->statistic) : riser->statistic;
    echo_until_s_ = t_s + options_.echo_window_s;
  }
  // Persistent leaders: the strongest peak at one direction frame after frame is a source,
  // whether or not it rose; a reflection seldom leads even one frame while its source sounds.
  const Vec3 first_u = peaks.empty() ? Vec3::Constant(DirectionPeak::kNan) : UnitOf(peaks.front());
  const bool persistent = Persists(&leader_, first_u) && may_start;
  plot_share_.clear();  // per peak: its statistic over the frame's strongest
  for (const DirectionPeak& peak : peaks)
    plot_share_.push_back(peaks.front().statistic > 0.0 ? peak.statistic / peaks.front().statistic : 0.0);
  // The same for the frame's second peak while it holds at least co_lead_share of the
  // strongest's statistic: a steady source beside a louder one ("Co-leaders").
  const bool second_counts =
      options_.co_lead_share > 0.0 && plot_share_.size() > 1 && plot_share_[1] >= options_.co_lead_share;
  const Vec3 second_u = second_counts ? UnitOf(peaks[1]) : Vec3::Constant(DirectionPeak::kNan);
  const bool persistent_second = Persists(&second_, second_u) && may_start;
  // It may resume a silent track, and start one only where no track of the last frame
  // (tentative too) lies within twice the gate.
  const bool persistent_starts = persistent && NoTrackNear(first_u);
  const bool persistent_second_starts = persistent_second && NoTrackNear(second_u);
  plots_.clear();
  for (const DirectionPeak& peak : peaks) {
    const Vec3 u = UnitOf(peak);
    if (!u.allFinite()) return InvalidArgument("a peak without a direction for this array's shape");
    tws::CartesianPlot plot;
    plot.position_m = u;
    const bool first = &peak == &peaks.front();
    const bool second = peaks.size() > 1 && &peak == &peaks[1];
    // A source that sounds on without onsets (a steady one whose track was lost) is still
    // the frame's strongest peak: when no confirmed track has been heard for
    // lost_source_after_s, it may start a track on a frame whose power did not fall.
    const bool strongest = options_.lost_source_after_s > 0.0 && unheard_s_ >= options_.lost_source_after_s && first;
    plot.may_start_track =
        !options_.start_at_onsets_only ||
        (may_start && ((!echo_blocks && &peak == riser && peak.rise >= peak.threshold) || strongest)) ||
        (first && persistent_starts) || (second && persistent_second_starts);
    // Read only when resume_after_s > 0.
    plot.may_resume_track = peak.rise >= peak.threshold || (first && persistent) || (second && persistent_second);
    if (linear) {
      const Mat3 radial = u * u.transpose();
      plot.covariance_m2 = s2 * (Mat3::Identity() - radial) + kRadialShare * kRadialShare * s2 * radial;
      plot.covariance_m2(2, 2) = s2;  // unused by a 2-D tracker; keeps it definite
    } else {
      plot.covariance_m2 = PeakCovariance(u);
    }
    plots_.push_back(plot);
  }
  LOCALIZER_RETURN_IF_ERROR(tracker_->ProcessCartesian(t_s, plots_));
  tracker_->Tracks(&reports_, true);
  UpdateLineages(t_s, riser && riser->rise >= riser->threshold ? riser : nullptr);
  bool heard = false;
  out->clear();
  for (const tws::TrackReport& r : reports_) {
    const Lineage& l = lineage_[r.id];
    if (!l.shown) continue;
    if (r.status != tws::TrackStatus::kTentative && !Leads(l)) continue;  // a reflection ("Leading")
    heard |= r.status == tws::TrackStatus::kConfirmed;
    if (r.status == tws::TrackStatus::kTentative && !include_tentative) continue;
    SourceTrack track;
    track.id = l.reported_id;
    track.status = r.status;
    track.hit_bits = l.hit_bits;
    track.led = l.led;
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
      track.azimuth_rad = AzimuthRad(u);
      track.elevation_rad = ElevationRad(u);
    }
    out->push_back(track);
  }
  unheard_s_ = heard ? 0.0 : unheard_s_ + options_.frame_period_s;
  std::sort(out->begin(), out->end(), [](const SourceTrack& a, const SourceTrack& b) { return a.id < b.id; });
  return Status::Ok();
}

}  // namespace localizer::engine
