#include "engine/pipeline/session_config.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace localizer::engine {
namespace {

std::string Num(double v) { return std::to_string(v); }

// The one tracker field that depends on another: the motion model applies to ekf and ukf.
Status ValidateTrackerKind(const TrackerOptions& t) {
  if (!IsSingleKalman(t.kind) && t.kalman.motion_model != MotionModelKind::kCv) {
    return InvalidArgument(std::string("motion_model '") + MotionModelKindName(t.kalman.motion_model) +
                           "' needs filter ekf or ukf (pf and mmpf set their own models, imm takes imm_modes)");
  }
  return Status::Ok();
}

}  // namespace

StatusOr<Localization> ParseLocalization(const std::string& name, const std::string& field) {
  if (name == "auto") return Localization::kAuto;
  if (name == "position") return Localization::kPosition;
  if (name == "direction") return Localization::kDirection;
  return InvalidArgument(field + " '" + name + "' is not one of: auto, position, direction");
}

const char* LocalizationName(Localization l) {
  return l == Localization::kAuto ? "auto" : l == Localization::kPosition ? "position" : "direction";
}

Status DetectionSessionConfig::Validate() const { return tws.Validate(); }

Status AudioSessionConfig::Validate() const {
  LOCALIZER_RETURN_IF_ERROR(ValidateTrackerKind(tracker));
  if (array_in_body_frame) {
    if (const Status s = attitude.Validate(); !s.ok()) return InvalidArgument("platform.attitude: " + s.message());
    if (!platform_origin_m.allFinite()) return InvalidArgument("platform.origin_m must be finite");
  }
  if (sensors_m.size() < 2) {
    return InvalidArgument("array.sensors_m has " + std::to_string(sensors_m.size()) +
                           " sensors; at least 2 are needed");
  }
  if (max_sources < 0 || max_sources > 16) {
    return InvalidArgument("max_sources must be in [1, 16] (0: not stated), got " + std::to_string(max_sources));
  }
  if (!source_side.allFinite()) return InvalidArgument("source_side must be finite");
  if (!source_plane_point_m.allFinite() || !source_plane_normal.allFinite()) {
    return InvalidArgument("source_plane must be finite");
  }
  if (!(sample_rate_hz > 0.0) || !std::isfinite(sample_rate_hz) || sample_rate_hz > 10e6) {
    return InvalidArgument("sample_rate_hz must be in (0, 1e7], got " + Num(sample_rate_hz));
  }
  if (!(sound_speed_mps > 0.0) || !std::isfinite(sound_speed_mps)) {
    return InvalidArgument("sound_speed_mps must be positive, got " + Num(sound_speed_mps));
  }
  if (frame_samples < 64 || frame_samples > (1 << 20)) {
    return InvalidArgument("frame_samples must be in [64, 1048576], got " + std::to_string(frame_samples));
  }
  if (hop_samples < 1 || hop_samples > frame_samples) {
    return InvalidArgument("hop_samples must be in [1, frame_samples=" + std::to_string(frame_samples) + "], got " +
                           std::to_string(hop_samples));
  }
  if (max_block_samples < 1) {
    return InvalidArgument("max_block_samples must be >= 1, got " + std::to_string(max_block_samples));
  }
  if (!(min_pair_quality >= 0.0)) return InvalidArgument("min_pair_quality must be >= 0, got " + Num(min_pair_quality));
  if (!(max_fix_std_m >= 0.0)) return InvalidArgument("max_fix_std_m must be >= 0, got " + Num(max_fix_std_m));
  if (!(init_speed_sigma_mps >= 0.0)) {
    return InvalidArgument("init_speed_sigma_mps must be >= 0, got " + Num(init_speed_sigma_mps));
  }
  if (divergence_window < 1) {
    return InvalidArgument("divergence_window must be >= 1, got " + std::to_string(divergence_window));
  }
  const bool region_set = init_region_min_m.allFinite() || init_region_max_m.allFinite();
  if (region_set && (!init_region_min_m.allFinite() || !init_region_max_m.allFinite() ||
                     (init_region_max_m - init_region_min_m).minCoeff() < 0.0)) {
    return InvalidArgument("init_region_min_m/init_region_max_m must both be finite with min <= max");
  }
  if (!(despike_k == 0.0 || (despike_k >= 1.0 && despike_k <= 1e6))) {
    return InvalidArgument("despike_k must be 0 (off) or in [1, 1e6], got " + Num(despike_k));
  }
  for (int i = 0; i < 3; ++i) {
    const double lo = bounds_min_m(i), hi = bounds_max_m(i);
    if (std::isnan(lo) || std::isnan(hi) || lo == std::numeric_limits<double>::infinity() ||
        hi == -std::numeric_limits<double>::infinity() || !(lo < hi) || (std::isfinite(lo) && std::abs(lo) > 1e7) ||
        (std::isfinite(hi) && std::abs(hi) > 1e7)) {
      return InvalidArgument("bounds on axis " + std::to_string(i) + " must be lo < hi, each finite within 1e7 m or " +
                             "unbounded (-inf / +inf), got [" + Num(lo) + ", " + Num(hi) + "]");
    }
  }
  if (!(search_radius_m >= 0.0) || search_radius_m > 1e7) {
    return InvalidArgument("search_radius_m must be in [0, 1e7], got " + Num(search_radius_m));
  }
  if (direction_search_starts < 1 || direction_search_starts > 64) {
    return InvalidArgument("direction_search_starts must be in [1, 64], got " +
                           std::to_string(direction_search_starts));
  }
  if (!(direction_co_lead_share >= 0.0 && direction_co_lead_share <= 1.0)) {
    return InvalidArgument("direction_co_lead_share must be in [0, 1], got " + Num(direction_co_lead_share));
  }
  if (!(direction_present_drop_db >= 0.0 && direction_present_drop_db <= 60.0)) {
    return InvalidArgument("direction_present_drop_db must be in [0, 60] dB, got " + Num(direction_present_drop_db));
  }
  if (!(direction_present_hold_s >= 0.0 && direction_present_hold_s <= 1.0)) {
    return InvalidArgument("direction_present_hold_s must be in [0, 1] s, got " + Num(direction_present_hold_s));
  }
  if (!(presence_false_alarm > 0.0) || presence_false_alarm > 0.1) {
    return InvalidArgument("presence_false_alarm must be in (0, 0.1], got " + Num(presence_false_alarm));
  }
  if (!(source_timeout_s > 0.0) || source_timeout_s > 1e6) {
    return InvalidArgument("source_timeout_s must be in (0, 1e6], got " + Num(source_timeout_s));
  }
  return tracker.particle.Validate();
}

double FramingTaperFraction(int frame_samples, int hop_samples) {
  if (frame_samples <= 0) return GccOptions().taper_fraction;
  const double overlap_taper = 2.0 * (1.0 - static_cast<double>(hop_samples) / frame_samples);
  return std::clamp(overlap_taper, GccOptions().taper_fraction, 1.0);
}

GccOptions AudioSessionConfig::GccOptionsFor() const {
  GccOptions gcc;
  gcc.frame_samples = frame_samples;
  gcc.sample_rate_hz = sample_rate_hz;
  gcc.weighting = weighting;
  gcc.phat_beta = phat_beta;
  gcc.band_low_hz = band_low_hz;
  gcc.band_high_hz = band_high_hz;
  gcc.taper_fraction = FramingTaperFraction(frame_samples, hop_samples);
  gcc.keep_gcc = true;     // acquisition, presence, multipath association and the noise anchor read it
  gcc.max_candidates = 1;  // the session looks for other peaks in the kept GCC, near its track
  gcc.cross_pairs_max_sensors = cross_pairs_max_sensors;
  // The closure check reads them on every frame (session_tracking.cc: CheckClosure, or the
  // acquisition search): measured with the frame's pairs, their transforms packed together.
  gcc.cross_pairs_with_frame = pair_closure || pair_fusion;
  return gcc;
}

}  // namespace localizer::engine
