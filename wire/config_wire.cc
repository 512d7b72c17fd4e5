#include "wire/config_wire.h"

#include <cmath>
#include <limits>
#include <sstream>
#include <variant>

#include "wire/filter_config_wire.h"
#include "wire/string_limits.h"

namespace localizer::wire {
namespace {

using engine::Vec3;

Vec3 FromProto(const v1::Vector3& v) { return {v.x(), v.y(), v.z()}; }

void ToProto(const Vec3& v, v1::Vector3* out) {
  out->set_x(v.x());
  out->set_y(v.y());
  out->set_z(v.z());
}

engine::Weighting WeightingFromProto(v1::Weighting w) {
  switch (w) {
    case v1::WEIGHTING_PHAT_BETA:
      return engine::Weighting::kPhatBeta;
    case v1::WEIGHTING_SCOT:
      return engine::Weighting::kScot;
    case v1::WEIGHTING_CC:
      return engine::Weighting::kCc;
    case v1::WEIGHTING_PHAT_COHERENCE:
      return engine::Weighting::kPhatCoherence;
    case v1::WEIGHTING_PHAT_SHARE:
      return engine::Weighting::kPhatShare;
    default:
      return engine::Weighting::kPhat;
  }
}

v1::Weighting WeightingToProto(engine::Weighting w) {
  switch (w) {
    case engine::Weighting::kPhatBeta:
      return v1::WEIGHTING_PHAT_BETA;
    case engine::Weighting::kScot:
      return v1::WEIGHTING_SCOT;
    case engine::Weighting::kCc:
      return v1::WEIGHTING_CC;
    case engine::Weighting::kPhatCoherence:
      return v1::WEIGHTING_PHAT_COHERENCE;
    case engine::Weighting::kPhatShare:
      return v1::WEIGHTING_PHAT_SHARE;
    case engine::Weighting::kPhat:
      break;
  }
  return v1::WEIGHTING_PHAT;
}

// Proto field names for the engine's field names in validation messages.
Status Rename(Status status) {
  if (status.ok()) return status;
  std::string m = status.message();
  const std::pair<const char*, const char*> renames[] = {
      {"sensors_m", "array.sensors_m"},
      {"sound_speed_mps", "array.sound_speed_mps"},
      {"reference_sensor", "array.reference_sensor"},
      {"particles", "filter.particles"},
      {"accel_noise_mps2", "filter.accel_noise_mps2"},
      {"tdoa_sigma_s", "filter.tdoa_sigma_s"},
      {"resample_threshold", "filter.resample_threshold"},
      {"min_peak_snr", "filter.min_peak_snr"},
      {"manoeuvre_share", "filter.manoeuvre_share"},
      {"manoeuvre_scale", "filter.manoeuvre_scale"},
      {"accel_level_floor", "filter.accel_level_floor"},
      {"accel_level_switch_hz", "filter.accel_level_switch_hz"},
  };
  for (const auto& [from, to] : renames) {
    const size_t at = m.find(from);
    if (at != std::string::npos && (at == 0 || m[at - 1] == ' ') && m.find(to) == std::string::npos) {
      m.replace(at, std::string(from).size(), to);
      break;
    }
  }
  return {status.code(), m};
}

std::string Num(double v) {
  std::ostringstream out;
  out.precision(17);
  out << v;
  return out.str();
}

// Bounds -> the engine's box: an unset side is open (+-infinity), as is a side set to
// infinity in its open direction; anything else must be finite, within 1e7 m, and each
// axis's min < max. Errors name the proto field ("bounds.max_z_m").
Status BoundsFromProto(const v1::Bounds& b, engine::AudioSessionConfig* c) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  struct Axis {
    const char* name;
    bool has_min, has_max;
    double min, max;
  };
  const Axis axes[3] = {{"x", b.has_min_x_m(), b.has_max_x_m(), b.min_x_m(), b.max_x_m()},
                        {"y", b.has_min_y_m(), b.has_max_y_m(), b.min_y_m(), b.max_y_m()},
                        {"z", b.has_min_z_m(), b.has_max_z_m(), b.min_z_m(), b.max_z_m()}};
  for (int i = 0; i < 3; ++i) {
    const Axis& a = axes[i];
    const std::string min_name = std::string("bounds.min_") + a.name + "_m";
    const std::string max_name = std::string("bounds.max_") + a.name + "_m";
    const double lo = a.has_min ? a.min : -kInf;
    const double hi = a.has_max ? a.max : kInf;
    const auto check = [](const std::string& name, double v, double open) -> Status {
      if (v == open) return Status::Ok();
      if (!std::isfinite(v) || std::abs(v) > 1e7) {
        return InvalidArgument(name + " is " + Num(v) + "; must be finite within 1e7 m, or " +
                               (open > 0 ? "+inf" : "-inf") + " / unset for unbounded");
      }
      return Status::Ok();
    };
    LOCALIZER_RETURN_IF_ERROR(check(min_name, lo, -kInf));
    LOCALIZER_RETURN_IF_ERROR(check(max_name, hi, kInf));
    if (!(lo < hi)) {
      return InvalidArgument(min_name + " (" + Num(lo) + ") must be below " + max_name + " (" + Num(hi) + ")");
    }
    c->bounds_min_m(i) = lo;
    c->bounds_max_m(i) = hi;
  }
  return Status::Ok();
}

void BoundsToProto(const engine::AudioSessionConfig& c, v1::SessionConfig* p) {
  if (c.bounds_min_m.array().isInf().all() && c.bounds_max_m.array().isInf().all()) return;  // unbounded
  v1::Bounds* b = p->mutable_bounds();
  if (std::isfinite(c.bounds_min_m.x())) b->set_min_x_m(c.bounds_min_m.x());
  if (std::isfinite(c.bounds_max_m.x())) b->set_max_x_m(c.bounds_max_m.x());
  if (std::isfinite(c.bounds_min_m.y())) b->set_min_y_m(c.bounds_min_m.y());
  if (std::isfinite(c.bounds_max_m.y())) b->set_max_y_m(c.bounds_max_m.y());
  if (std::isfinite(c.bounds_min_m.z())) b->set_min_z_m(c.bounds_min_m.z());
  if (std::isfinite(c.bounds_max_m.z())) b->set_max_z_m(c.bounds_max_m.z());
}

// Client strings within their documented lengths (string_limits.h), before anything
// reads them.
Status CheckStrings(const v1::SessionConfig& p) {
  LOCALIZER_RETURN_IF_ERROR(CheckLength("label", p.label(), kMaxLabelBytes));
  LOCALIZER_RETURN_IF_ERROR(CheckLength("backend", p.backend(), kMaxEnumStringBytes));
  LOCALIZER_RETURN_IF_ERROR(CheckLength("localization", p.localization(), kMaxEnumStringBytes));
  const v1::FilterConfig& f = p.filter();
  LOCALIZER_RETURN_IF_ERROR(CheckLength("filter.motion_model", f.motion_model(), kMaxEnumStringBytes));
  LOCALIZER_RETURN_IF_ERROR(CheckLength("filter.imm_modes", f.imm_modes(), kMaxEnumStringBytes));
  LOCALIZER_RETURN_IF_ERROR(CheckLength("filter.imm_variant", f.imm_variant(), kMaxEnumStringBytes));
  LOCALIZER_RETURN_IF_ERROR(CheckLength("filter.robust", f.robust(), kMaxEnumStringBytes));
  LOCALIZER_RETURN_IF_ERROR(
      CheckLength("platform.attitude_filter", p.platform().attitude_filter(), kMaxEnumStringBytes));
  return Status::Ok();
}

// A proto3 enum field holds any int32; a value outside the enum is refused, never read as
// the default.
template <typename IsValid>
Status CheckEnum(const char* field, int value, IsValid is_valid, const char* allowed) {
  if (is_valid(value)) return Status::Ok();
  return InvalidArgument(std::string(field) + " is " + std::to_string(value) + ", not a known value (" + allowed + ")");
}

Status CheckEnums(const v1::SessionConfig& p) {
  LOCALIZER_RETURN_IF_ERROR(CheckEnum("weighting", p.weighting(), v1::Weighting_IsValid,
                                      "PHAT, PHAT_BETA, SCOT, CC, PHAT_COHERENCE, PHAT_SHARE"));
  LOCALIZER_RETURN_IF_ERROR(
      CheckEnum("filter.type", p.filter().type(), v1::FilterType_IsValid, "PF, EKF, UKF, MMPF, IMM"));
  LOCALIZER_RETURN_IF_ERROR(
      CheckEnum("filter.likelihood", p.filter().likelihood(), v1::Likelihood_IsValid, "PEAK, GCC, MIXTURE"));
  return Status::Ok();
}

// init_region: finite, within 1e7 m (as the bounds), min <= max on every axis.
Status InitRegionFromProto(const v1::Region& r, engine::AudioSessionConfig* c) {
  const double lo[3] = {r.min_m().x(), r.min_m().y(), r.min_m().z()};
  const double hi[3] = {r.max_m().x(), r.max_m().y(), r.max_m().z()};
  const char* const axes[3] = {"x", "y", "z"};
  for (int i = 0; i < 3; ++i) {
    for (const auto& [side, v] : {std::pair<const char*, double>{"min_m", lo[i]}, {"max_m", hi[i]}}) {
      if (!std::isfinite(v) || std::abs(v) > 1e7) {
        return InvalidArgument(std::string("init_region.") + side + "." + axes[i] + " is " + Num(v) +
                               "; must be finite within 1e7 m");
      }
    }
    if (lo[i] > hi[i]) {
      return InvalidArgument(std::string("init_region.min_m.") + axes[i] + " (" + Num(lo[i]) +
                             ") must be <= init_region.max_m." + axes[i] + " (" + Num(hi[i]) + ")");
    }
  }
  c->init_region_min_m = FromProto(r.min_m());
  c->init_region_max_m = FromProto(r.max_m());
  return Status::Ok();
}

}  // namespace

namespace {

// A count the client may lower but not raise above the server's limit (0: the limit).
Status BoundedCount(uint32_t requested, int limit, const char* field, const char* flag, int* out) {
  if (requested > static_cast<uint32_t>(limit)) {
    return InvalidArgument(std::string(field) + " is " + std::to_string(requested) + "; this server allows at most " +
                           std::to_string(limit) + " (" + flag + ")");
  }
  *out = requested != 0 ? static_cast<int>(requested) : limit;
  return Status::Ok();
}

// DetectionConfig -> the tracker's options; zero fields keep the defaults.
StatusOr<engine::DetectionSessionConfig> DetectionConfigFromProto(const v1::SessionConfig& p,
                                                                  const ConfigPolicy& policy) {
  engine::DetectionSessionConfig c;
  c.seed = p.has_seed() ? p.seed() : 1;
  const v1::DetectionConfig& d = p.detections();
  engine::tws::TwsOptions& o = c.tws;
  if (d.dimensions() != 0) o.dimensions = static_cast<int>(std::min<uint32_t>(d.dimensions(), 1000));
  if (d.range_sigma_m() != 0.0) o.noise.range_sigma_m = d.range_sigma_m();
  if (d.bearing_sigma_rad() != 0.0) o.noise.bearing_sigma_rad = d.bearing_sigma_rad();
  if (d.elevation_sigma_rad() != 0.0) o.noise.elevation_sigma_rad = d.elevation_sigma_rad();
  if (d.accel_noise_mps2() != 0.0) o.accel_noise_mps2 = d.accel_noise_mps2();
  o.filter = d.steady_state_gain() ? engine::tws::FilterForm::kSteadyState : engine::tws::FilterForm::kKalman;
  if (d.gate_probability() != 0.0) o.gate_probability = d.gate_probability();
  if (d.confirm_hits() != 0) o.confirm_hits = static_cast<int>(std::min<uint32_t>(d.confirm_hits(), 1000));
  if (d.confirm_window() != 0) o.confirm_window = static_cast<int>(std::min<uint32_t>(d.confirm_window(), 1000));
  if (d.max_coast_scans() != 0) o.max_coast_scans = static_cast<int>(std::min<uint32_t>(d.max_coast_scans(), 100000));
  if (d.max_position_sigma_m() != 0.0) o.max_position_sigma_m = d.max_position_sigma_m();
  o.initiation = d.two_point_initiation() ? engine::tws::Initiation::kTwoPoint : engine::tws::Initiation::kOnePoint;
  if (d.initial_speed_sigma_mps() != 0.0) o.initial_speed_sigma_mps = d.initial_speed_sigma_mps();
  if (d.max_speed_mps() != 0.0) o.max_speed_mps = d.max_speed_mps();
  LOCALIZER_RETURN_IF_ERROR(
      BoundedCount(d.max_tracks(), policy.max_tracks, "detections.max_tracks", "--max-tracks", &o.max_tracks));
  LOCALIZER_RETURN_IF_ERROR(BoundedCount(d.max_plots_per_scan(), policy.max_plots_per_scan,
                                         "detections.max_plots_per_scan", "--max-scan-plots", &o.max_plots_per_scan));
  if (const Status s = c.Validate(); !s.ok()) return InvalidArgument("detections: " + s.message());
  return c;
}

}  // namespace

StatusOr<engine::SessionConfig> ConfigFromProto(const v1::SessionConfig& p, const ConfigPolicy& policy) {
  if (p.has_detections()) {
    LOCALIZER_RETURN_IF_ERROR(CheckStrings(p));
    auto detection = DetectionConfigFromProto(p, policy);
    if (!detection.ok()) return detection.status();
    return engine::SessionConfig(*std::move(detection));
  }
  auto audio = AudioConfigFromProto(p, policy);
  if (!audio.ok()) return audio.status();
  return engine::SessionConfig(*std::move(audio));
}

StatusOr<engine::AudioSessionConfig> AudioConfigFromProto(const v1::SessionConfig& p, const ConfigPolicy& policy) {
  LOCALIZER_RETURN_IF_ERROR(CheckStrings(p));
  if (p.has_detections()) {
    return InvalidArgument("detections: an audio session's config has an array and samples, not detections");
  }
  LOCALIZER_RETURN_IF_ERROR(CheckEnums(p));
  engine::AudioSessionConfig c;
  if (!p.has_array()) return InvalidArgument("array is missing");
  if (p.array().sensors_m_size() > policy.max_channels) {
    return InvalidArgument("array.sensors_m has " + std::to_string(p.array().sensors_m_size()) +
                           " sensors; this server allows at most " + std::to_string(policy.max_channels));
  }
  for (const v1::Vector3& s : p.array().sensors_m()) c.sensors_m.push_back(FromProto(s));
  c.sound_speed_mps = p.array().sound_speed_mps();
  // Unsigned on the wire: checked (and printed) as such before the engine's int.
  if (p.array().sensors_m_size() > 0 &&
      p.array().reference_sensor() >= static_cast<uint32_t>(p.array().sensors_m_size())) {
    return InvalidArgument("array.reference_sensor is " + std::to_string(p.array().reference_sensor()) +
                           "; must be below the sensor count " + std::to_string(p.array().sensors_m_size()));
  }
  c.reference_sensor = static_cast<int>(p.array().reference_sensor());
  c.sample_rate_hz = p.sample_rate_hz();
  if (p.frame_samples() > (1u << 20)) {
    return InvalidArgument("frame_samples is " + std::to_string(p.frame_samples()) + "; must be in [64, 1048576]");
  }
  if (p.frame_samples() != 0) c.frame_samples = static_cast<int>(p.frame_samples());
  c.hop_samples = p.hop_samples() != 0 ? static_cast<int>(std::min<uint32_t>(p.hop_samples(), 1u << 21))
                                       : std::max(1, c.frame_samples / 2);
  if (const int min_hop = std::max(1, c.frame_samples / policy.max_frame_overlap); c.hop_samples < min_hop) {
    return InvalidArgument("hop_samples is " + std::to_string(c.hop_samples) + "; this server requires at least " +
                           "frame_samples/" + std::to_string(policy.max_frame_overlap) + " = " +
                           std::to_string(min_hop));
  }
  c.weighting = WeightingFromProto(p.weighting());
  if (p.phat_beta() != 0.0) c.phat_beta = p.phat_beta();
  c.band_low_hz = p.band_low_hz();
  c.band_high_hz = p.band_high_hz();

  LOCALIZER_RETURN_IF_ERROR(TrackerFromProto(p.filter(), policy, &c.tracker));
  auto backend = engine::ParseBackendChoice(p.backend().empty() ? policy.default_backend : p.backend(), "backend");
  if (!backend.ok()) return NameRefusal(backend.status());
  c.backend = *backend;
  if (p.has_seed()) c.seed = p.seed();
  if (p.has_init_region()) LOCALIZER_RETURN_IF_ERROR(InitRegionFromProto(p.init_region(), &c));
  if (p.min_pair_quality() != 0.0) c.min_pair_quality = p.min_pair_quality();
  c.max_fix_std_m = p.max_fix_std_m();
  if (p.max_block_samples() > policy.max_block_samples) {
    return InvalidArgument("max_block_samples is " + std::to_string(p.max_block_samples()) +
                           "; this server allows at most " + std::to_string(policy.max_block_samples));
  }
  c.max_block_samples = p.max_block_samples() != 0 ? p.max_block_samples() : policy.max_block_samples;
  if (p.has_bounds()) LOCALIZER_RETURN_IF_ERROR(BoundsFromProto(p.bounds(), &c));
  c.search_radius_m = p.search_radius_m();
  if (p.presence_false_alarm() != 0.0) c.presence_false_alarm = p.presence_false_alarm();
  if (p.source_timeout_s() != 0.0) c.source_timeout_s = p.source_timeout_s();
  if (p.has_despike_k()) c.despike_k = p.despike_k();
  auto localization = engine::ParseLocalization(p.localization().empty() ? "auto" : p.localization(), "localization");
  if (!localization.ok()) return NameRefusal(localization.status());
  c.localization = *localization;
  if (p.has_max_sources()) {
    if (p.max_sources() < 1 || p.max_sources() > 16) {
      return InvalidArgument("max_sources is " + std::to_string(p.max_sources()) + "; must be in [1, 16]");
    }
    c.max_sources = static_cast<int>(p.max_sources());
  }
  if (p.has_source_side()) c.source_side = FromProto(p.source_side());
  if (p.has_direction_present_hold_s()) c.direction_present_hold_s = p.direction_present_hold_s();
  if (p.has_direction_diffuse_weighting()) c.direction_diffuse_weighting = p.direction_diffuse_weighting();
  if (p.has_direction_signal_weighting()) c.direction_signal_weighting = p.direction_signal_weighting();
  if (p.has_source_plane()) {
    c.source_plane_point_m = FromProto(p.source_plane().point_m());
    c.source_plane_normal = FromProto(p.source_plane().normal());
    if (c.source_plane_normal == Vec3::Zero()) return InvalidArgument("source_plane.normal must not be zero");
  }
  if (p.has_platform()) {
    const v1::PlatformConfig& platform = p.platform();
    c.array_in_body_frame = true;
    auto kind =
        engine::ParseAttitudeFilterKind(platform.attitude_filter().empty() ? "quaternion" : platform.attitude_filter());
    if (!kind.ok()) return NameRefusal(InvalidArgument("platform.attitude_filter: " + kind.status().message()));
    c.attitude.kind = *kind;
    c.attitude.use_mag = platform.use_magnetometer();
    c.attitude.mag_declination_rad = platform.mag_declination_rad();
    c.platform_origin_m = FromProto(platform.origin_m());
  }
  LOCALIZER_RETURN_IF_ERROR(Rename(c.Validate()));
  return c;
}

v1::SessionConfig ConfigToProto(const engine::SessionConfig& config, const std::string& label) {
  return std::visit([&](const auto& kind) { return ConfigToProto(kind, label); }, config);
}

v1::SessionConfig ConfigToProto(const engine::DetectionSessionConfig& c, const std::string& label) {
  v1::SessionConfig p;
  const engine::tws::TwsOptions& o = c.tws;
  v1::DetectionConfig* d = p.mutable_detections();
  d->set_dimensions(static_cast<uint32_t>(o.dimensions));
  d->set_range_sigma_m(o.noise.range_sigma_m);
  d->set_bearing_sigma_rad(o.noise.bearing_sigma_rad);
  d->set_elevation_sigma_rad(o.noise.elevation_sigma_rad);
  d->set_accel_noise_mps2(o.accel_noise_mps2);
  d->set_steady_state_gain(o.filter == engine::tws::FilterForm::kSteadyState);
  d->set_gate_probability(o.gate_probability);
  d->set_confirm_hits(static_cast<uint32_t>(o.confirm_hits));
  d->set_confirm_window(static_cast<uint32_t>(o.confirm_window));
  d->set_max_coast_scans(static_cast<uint32_t>(o.max_coast_scans));
  d->set_max_position_sigma_m(o.max_position_sigma_m);
  d->set_two_point_initiation(o.initiation == engine::tws::Initiation::kTwoPoint);
  d->set_initial_speed_sigma_mps(o.initial_speed_sigma_mps);
  d->set_max_speed_mps(o.max_speed_mps);
  d->set_max_tracks(static_cast<uint32_t>(o.max_tracks));
  d->set_max_plots_per_scan(static_cast<uint32_t>(o.max_plots_per_scan));
  p.set_backend("cpu");  // detection sessions run on the CPU
  p.set_seed(c.seed);
  p.set_label(label);
  return p;
}

v1::SessionConfig ConfigToProto(const engine::AudioSessionConfig& c, const std::string& label) {
  v1::SessionConfig p;
  for (const Vec3& s : c.sensors_m) ToProto(s, p.mutable_array()->add_sensors_m());
  p.mutable_array()->set_sound_speed_mps(c.sound_speed_mps);
  p.mutable_array()->set_reference_sensor(static_cast<uint32_t>(c.reference_sensor));
  p.set_sample_rate_hz(c.sample_rate_hz);
  p.set_frame_samples(static_cast<uint32_t>(c.frame_samples));
  p.set_hop_samples(static_cast<uint32_t>(c.hop_samples));
  p.set_weighting(WeightingToProto(c.weighting));
  p.set_phat_beta(c.phat_beta);
  p.set_band_low_hz(c.band_low_hz);
  p.set_band_high_hz(c.band_high_hz);
  TrackerToProto(c.tracker, p.mutable_filter());
  p.set_backend(engine::BackendChoiceName(c.backend));
  p.set_seed(c.seed);
  p.set_label(label);
  if (c.init_region_min_m.allFinite() && c.init_region_max_m.allFinite()) {
    ToProto(c.init_region_min_m, p.mutable_init_region()->mutable_min_m());
    ToProto(c.init_region_max_m, p.mutable_init_region()->mutable_max_m());
  }
  p.set_min_pair_quality(c.min_pair_quality);
  p.set_max_fix_std_m(c.max_fix_std_m);
  p.set_max_block_samples(static_cast<uint32_t>(std::min<int64_t>(c.max_block_samples, UINT32_MAX)));
  BoundsToProto(c, &p);
  p.set_search_radius_m(c.search_radius_m);
  p.set_presence_false_alarm(c.presence_false_alarm);
  p.set_source_timeout_s(c.source_timeout_s);
  p.set_despike_k(c.despike_k);
  p.set_localization(engine::LocalizationName(c.localization));
  if (c.max_sources > 0) p.set_max_sources(static_cast<uint32_t>(c.max_sources));
  if (c.source_side != Vec3::Zero()) ToProto(c.source_side, p.mutable_source_side());
  p.set_direction_present_hold_s(c.direction_present_hold_s);
  p.set_direction_diffuse_weighting(c.direction_diffuse_weighting);
  if (c.direction_signal_weighting) p.set_direction_signal_weighting(*c.direction_signal_weighting);
  if (c.source_plane_normal != Vec3::Zero()) {
    ToProto(c.source_plane_point_m, p.mutable_source_plane()->mutable_point_m());
    ToProto(c.source_plane_normal, p.mutable_source_plane()->mutable_normal());
  }
  if (c.array_in_body_frame) {
    v1::PlatformConfig* platform = p.mutable_platform();
    platform->set_attitude_filter(engine::AttitudeFilterKindName(c.attitude.kind));
    platform->set_use_magnetometer(c.attitude.use_mag);
    platform->set_mag_declination_rad(c.attitude.mag_declination_rad);
    ToProto(c.platform_origin_m, platform->mutable_origin_m());
  }
  return p;
}

}  // namespace localizer::wire
