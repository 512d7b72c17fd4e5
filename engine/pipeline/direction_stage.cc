#include "engine/pipeline/direction_stage.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <map>
#include <string>

namespace localizer::engine {
namespace {

constexpr int kMaxRiseFrames = 64;  // PairSpectraOptions::rise_lag_frames' ceiling

// Angle between a track and a peak: of directions, or of cone angles (linear arrays).
double Separation(const SourceTrack& track, const DirectionPeak& peak) {
  if (std::isfinite(track.cone_angle_rad)) return std::abs(track.cone_angle_rad - peak.cone_angle_rad);
  return std::atan2(track.direction.cross(peak.direction).norm(), track.direction.dot(peak.direction));
}

// Drops the entries of tracks no longer reported (deleted, or hidden as echoes).
template <typename Value>
void ForgetUnreported(const std::vector<SourceTrack>& tracks, std::map<uint64_t, Value>* by_id) {
  std::erase_if(*by_id, [&](const auto& entry) {
    return std::none_of(tracks.begin(), tracks.end(), [&](const SourceTrack& t) { return t.id == entry.first; });
  });
}

}  // namespace

NearFieldOptions NearFieldOptionsFor(const AudioSessionConfig& config) {
  NearFieldOptions near;
  near.sample_rate_hz = config.sample_rate_hz;
  near.sound_speed_mps = config.sound_speed_mps;
  near.source_side = config.source_side;
  near.plane_point_m = config.source_plane_point_m;
  near.plane_normal = config.source_plane_normal;
  return near;
}

StatusOr<std::unique_ptr<DirectionStage>> DirectionStage::Create(const AudioSessionConfig& config, bool positions) {
  // Rises look back over the frames that overlap this one: at most kMaxRiseFrames of them.
  if (config.hop_samples * kMaxRiseFrames < config.frame_samples) {
    return InvalidArgument("hop_samples is " + std::to_string(config.hop_samples) +
                           "; direction sessions need at least frame_samples/" + std::to_string(kMaxRiseFrames) +
                           " = " + std::to_string((config.frame_samples + kMaxRiseFrames - 1) / kMaxRiseFrames));
  }
  SrpOptions srp;
  srp.sample_rate_hz = config.sample_rate_hz;
  srp.sound_speed_mps = config.sound_speed_mps;
  srp.frame_samples = config.frame_samples;
  srp.band_low_hz = config.band_low_hz;
  srp.band_high_hz = config.band_high_hz;
  srp.max_sources = config.EffectiveMaxSources();
  srp.false_alarm = config.presence_false_alarm;
  srp.source_side = config.source_side;
  srp.hop_samples = config.hop_samples;  // onsets: the rise against the last frame not overlapping
  srp.keep_whole_field = positions;      // the near-field fits' coarse grid reads it
  srp.search_starts = config.direction_search_starts;
  srp.diffuse_weighting = config.direction_diffuse_weighting;
  {
    auto shape = ClassifyArray(config.sensors_m);
    if (!shape.ok()) return shape.status();
    srp.signal_weighting = config.direction_signal_weighting.value_or(DefaultSignalWeighting(shape->shape));
  }
  auto made = SrpPhat::Create(config.sensors_m, srp);
  if (!made.ok()) return made.status();
  DirectionTrackerOptions options;
  options.frame_period_s = config.hop_samples / config.sample_rate_hz;
  options.co_lead_share = config.direction_co_lead_share;
  // Onsets compare with the recent past, which must span at least one frame (long hops:
  // underwater frames of thousands of samples).
  options.onset_memory_s = std::max(options.onset_memory_s, options.frame_period_s);
  auto tracker = DirectionTracker::Create(made->shape(), options);
  if (!tracker.ok()) return tracker.status();
  std::optional<NearFieldLocator> near;
  if (positions) {
    auto locator = NearFieldLocator::Create(config.sensors_m, NearFieldOptionsFor(config));
    if (!locator.ok()) return locator.status();
    near = std::move(locator).value();
  }
  std::optional<EchoWatch> echoes;
  if (config.direction_echo_test) {
    EchoWatchOptions watch;
    watch.test.sample_rate_hz = config.sample_rate_hz;
    watch.test.sound_speed_mps = config.sound_speed_mps;
    watch.test.frame_samples = config.frame_samples;
    watch.test.band_low_hz = config.band_low_hz;
    watch.test.band_high_hz = config.band_high_hz;
    auto made_watch = EchoWatch::Create(config.sensors_m, made->shape(), watch);
    if (!made_watch.ok()) return made_watch.status();
    echoes = std::move(made_watch).value();
  }
  return std::unique_ptr<DirectionStage>(
      new DirectionStage(std::move(made).value(), std::move(tracker).value(), std::move(near), std::move(echoes),
                         config.direction_present_drop_db, config.direction_present_hold_s));
}

Vec3 DirectionStage::FitDirection(const SourceEstimate& source) const {
  return std::isfinite(source.cone_angle_rad) ? near_->DirectionAt(source.cone_angle_rad) : source.direction;
}

void DirectionStage::Apply(const NearFieldFix& fix, SourceEstimate* source) const {
  source->range_sd_m = fix.range_sd_m;
  if (!fix.near_field) return;
  source->position_m = fix.position_m;
  source->position_covariance_m2 = fix.covariance_m2;
  // The direction of a source with a position is the position's: the far-field one is
  // biased by the wavefront's curvature (near_field.h).
  const ArrayShapeInfo& shape = near_->shape();
  const Vec3 u = (fix.position_m - shape.centroid_m).normalized();
  if (std::isfinite(source->cone_angle_rad)) {
    source->cone_angle_rad = ConeAngleRad(u, shape.axis);
  } else {
    source->direction = u;
    source->azimuth_rad = AzimuthRad(u);
    source->elevation_rad = ElevationRad(u);
  }
}

void DirectionStage::LocateHeard(Estimate* e, size_t first) {
  heard_.clear();
  directions_.clear();
  fixes_.clear();
  for (size_t j = first; j < e->sources.size(); ++j) {
    if (!e->sources[j].source_present) continue;
    heard_.push_back(j);
    directions_.push_back(FitDirection(e->sources[j]));
    fixes_.push_back(near_->Locate(srp_.spectra(), srp_.whole_field(), directions_.back()));
  }
  if (heard_.size() >= 2) RefitAmongOthers();
  for (size_t k = 0; k < heard_.size(); ++k) Apply(fixes_[k], &e->sources[heard_[k]]);
}

void DirectionStage::RefitAmongOthers() {
  PairSpectra& spectra = srp_.mutable_spectra();
  const int pairs = spectra.pair_count();
  const Vec3& centroid_m = near_->shape().centroid_m;
  // Each source's lags from its first fit's end point (its direction's plane wave without a fit).
  lags_.assign(heard_.size() * static_cast<size_t>(pairs), 0.0);
  for (size_t k = 0; k < heard_.size(); ++k) {
    const Vec3 at_m =
        fixes_[k].fitted_m.allFinite() ? fixes_[k].fitted_m : Vec3(centroid_m + kPlaneWaveRange_m * directions_[k]);
    for (int p = 0; p < pairs; ++p) lags_[k * pairs + p] = near_->PairLag(spectra, p, at_m);
  }
  // FillFields rewrites every pair's lags; the field's shape is the whole field's.
  if (residual_field_.pairs.size() != srp_.whole_field().pairs.size()) residual_field_ = srp_.whole_field();
  for (size_t k = 0; k < heard_.size(); ++k) {
    spectra.ResetToWhole();
    for (size_t other = 0; other < heard_.size(); ++other) {
      if (other == k) continue;
      for (int p = 0; p < pairs; ++p) spectra.RemoveDelay(p, lags_[other * pairs + p], &taken_);
    }
    spectra.FillFields(&residual_field_);
    fixes_[k] = near_->Locate(spectra, residual_field_, directions_[k], NearFieldLocator::Spectrum::kCurrent);
  }
}

void DirectionStage::Frame(const float* frame, double t_s, Estimate* e) {
  auto peaks = srp_.Analyse(frame);  // the session validated the samples: cannot fail
  if (!peaks.ok()) peaks = std::vector<DirectionPeak>{};
  e->source_present = !peaks->empty();
  e->presence_statistic = peaks->empty() ? 0.0 : peaks->front().statistic;
  e->presence_threshold = srp_.threshold();
  if (!tracker_.Update(t_s, *peaks, srp_.band_power(), &tracks_).ok()) tracks_.clear();
  if (echoes_) {
    // A confirmed track took a peak this frame (a miss makes it coasting).
    heard_tracks_.assign(tracks_.size(), 0);
    for (size_t j = 0; j < tracks_.size(); ++j)
      heard_tracks_[j] = tracks_[j].status == TrackStatus::kConfirmed && !peaks->empty();
    echoes_->Frame(frame, tracks_, heard_tracks_);
    tracks_.erase(
        std::remove_if(tracks_.begin(), tracks_.end(), [&](const SourceTrack& t) { return echoes_->IsEcho(t.id); }),
        tracks_.end());
  }
  ForgetUnreported(tracks_, &track_level_db_);
  const size_t first = e->sources.size();
  for (const SourceTrack& track : tracks_) {
    SourceEstimate s;
    s.source_id = track.id;
    s.status = track.status;
    s.direction = track.direction;
    s.azimuth_rad = track.azimuth_rad;
    s.elevation_rad = track.elevation_rad;
    s.cone_angle_rad = track.cone_angle_rad;
    s.sigma_rad = track.sigma_rad;
    e->sources.push_back(s);
  }
  // A track that took a plot this frame (status confirmed; a miss makes it coasting) heard
  // its source, and reports the power of the peak nearest to it. The tracker's own
  // assignment decides, not a distance test here: a planar board's elevation is loose
  // (max_elevation_sigma_rad), so a peak it assigned can lie far from the track in 3-D angle.
  for (size_t j = 0; j < tracks_.size(); ++j) {
    const SourceTrack& track = tracks_[j];
    if (track.status != TrackStatus::kConfirmed || peaks->empty()) continue;
    SourceEstimate& heard = e->sources[first + j];
    heard.source_present = true;
    double nearest_rad = std::numeric_limits<double>::infinity();
    for (const DirectionPeak& peak : *peaks) {
      const double d = Separation(track, peak);
      if (d < nearest_rad) {
        nearest_rad = d;
        heard.power_db = peak.power_db;
      }
    }
    if (drop_db_ > 0.0) {
      // Present only near its own level (AudioSessionConfig::direction_present_drop_db); the
      // level follows the peaks it is present on, and slowly the others (a source that became
      // quieter for good is heard again after about 1.6 s at 62.5 frames per second).
      double& level_db = track_level_db_.try_emplace(track.id, heard.power_db).first->second;
      const bool far_below = heard.power_db < level_db - drop_db_;
      if (far_below) heard.source_present = false;
      level_db += (far_below ? kHiddenLevelWeight : kLevelWeight) * (heard.power_db - level_db);
    }
  }
  if (near_) LocateHeard(e, first);
  if (hold_s_ > 0.0) Hold(t_s, e, first);
}

void DirectionStage::Hold(double t_s, Estimate* e, size_t first) {
  ForgetUnreported(tracks_, &last_heard_);
  for (size_t j = 0; j < tracks_.size(); ++j) {
    const SourceTrack& track = tracks_[j];
    SourceEstimate& source = e->sources[first + j];
    if (source.source_present) {
      const int recent_hits = std::popcount(track.hit_bits & ((1u << kHoldWindowFrames) - 1u));
      last_heard_[track.id] = {t_s, track.led && recent_hits >= kHoldHits};
      continue;
    }
    // Coasting through a gap no longer than the hold, after a frame it led among a run of hits
    // (a talker between syllables; a track on a reflection seldom leads). Not after a level
    // drop: that frame's peak was the track's, and far below its source.
    const auto heard = last_heard_.find(track.id);
    if (heard != last_heard_.end() && heard->second.holds && track.status == TrackStatus::kCoasting &&
        t_s - heard->second.t_s <= hold_s_ + 1e-9) {
      source.source_present = true;
    }
  }
}

}  // namespace localizer::engine
