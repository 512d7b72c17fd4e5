#include "wire/filter_config_wire.h"

#include <algorithm>
#include <string>

#include "wire/string_limits.h"

namespace localizer::wire {
namespace {

// Which filter each proto filter type selects.
StatusOr<engine::FilterKind> FilterKindFromProto(v1::FilterType type) {
  switch (type) {
    case v1::FILTER_TYPE_UNSPECIFIED:
    case v1::FILTER_TYPE_PF:
      return engine::FilterKind::kPf;
    case v1::FILTER_TYPE_EKF:
      return engine::FilterKind::kEkf;
    case v1::FILTER_TYPE_UKF:
      return engine::FilterKind::kUkf;
    case v1::FILTER_TYPE_MMPF:
      return engine::FilterKind::kMmpf;
    case v1::FILTER_TYPE_IMM:
      return engine::FilterKind::kImm;
    default:
      break;
  }
  return InvalidArgument("filter.type " + std::to_string(type) + " is not one of: PF, EKF, UKF, MMPF, IMM");
}

v1::FilterType FilterKindToProto(engine::FilterKind kind) {
  switch (kind) {
    case engine::FilterKind::kEkf:
      return v1::FILTER_TYPE_EKF;
    case engine::FilterKind::kUkf:
      return v1::FILTER_TYPE_UKF;
    case engine::FilterKind::kMmpf:
      return v1::FILTER_TYPE_MMPF;
    case engine::FilterKind::kImm:
      return v1::FILTER_TYPE_IMM;
    case engine::FilterKind::kPf:
      break;
  }
  return v1::FILTER_TYPE_PF;
}

}  // namespace

Status TrackerFromProto(const v1::FilterConfig& f, const ConfigPolicy& policy, engine::TrackerOptions* t) {
  if (f.particles() > static_cast<uint32_t>(policy.max_particles)) {
    return InvalidArgument("filter.particles is " + std::to_string(f.particles()) + "; this server allows at most " +
                           std::to_string(policy.max_particles));
  }
  auto kind = FilterKindFromProto(f.type());
  if (!kind.ok()) return kind.status();
  t->kind = *kind;
  if (!f.motion_model().empty()) {
    auto model = engine::ParseMotionModelKind(f.motion_model(), "filter.motion_model");
    if (!model.ok()) return NameRefusal(model.status());
    t->kalman.motion_model = *model;
  }
  if (!f.imm_modes().empty()) {
    auto modes = engine::ParseImmModes(f.imm_modes(), "filter.imm_modes");
    if (!modes.ok()) return NameRefusal(modes.status());
    t->imm_modes = *std::move(modes);
  }
  if (!f.imm_variant().empty()) {
    auto variant = engine::ParseKalmanVariant(f.imm_variant(), "filter.imm_variant");
    if (!variant.ok()) return NameRefusal(variant.status());
    t->imm_variant = *variant;
  }
  if (!f.robust().empty()) {
    auto robust = engine::ParseRobustUpdate(f.robust(), "filter.robust");
    if (!robust.ok()) return NameRefusal(robust.status());
    t->kalman.robust = *robust;
  }
  engine::ParticleFilterOptions& particle = t->particle;
  if (f.particles() != 0) particle.particles = static_cast<int>(f.particles());
  if (f.accel_noise_mps2() != 0.0) particle.accel_noise_mps2 = f.accel_noise_mps2();
  particle.tdoa_sigma_s = f.tdoa_sigma_s();
  if (f.likelihood() == v1::LIKELIHOOD_GCC) particle.likelihood = engine::Likelihood::kGcc;
  if (f.likelihood() == v1::LIKELIHOOD_MIXTURE) particle.likelihood = engine::Likelihood::kMixture;
  if (f.outlier_probability() != 0.0) particle.outlier_probability = f.outlier_probability();
  if (f.has_manoeuvre_share()) particle.manoeuvre_share = f.manoeuvre_share();
  if (f.manoeuvre_scale() != 0.0) particle.manoeuvre_scale = f.manoeuvre_scale();
  if (f.accel_level_floor() != 0.0) particle.accel_level_floor = f.accel_level_floor();
  if (f.accel_level_ceiling() != 0.0) particle.accel_level_ceiling = f.accel_level_ceiling();
  if (f.accel_level_switch_hz() != 0.0) particle.accel_level_switch_hz = std::max(0.0, f.accel_level_switch_hz());
  if (f.turn_rate_max_radps() != 0.0) particle.turn_rate_max_radps = std::max(0.0, f.turn_rate_max_radps());
  if (f.speed_change_max_mps2() != 0.0) particle.speed_change_max_mps2 = std::max(0.0, f.speed_change_max_mps2());
  if (f.min_peak_snr() != 0.0) particle.min_peak_snr = f.min_peak_snr();
  if (f.resample_threshold() != 0.0) particle.resample_threshold = f.resample_threshold();
  t->kalman.motion.accel_noise_mps2 = particle.accel_noise_mps2;
  t->kalman.tdoa_sigma_s = particle.tdoa_sigma_s;
  t->kalman.min_peak_snr = particle.min_peak_snr;
  return Status::Ok();
}

void TrackerToProto(const engine::TrackerOptions& t, v1::FilterConfig* f) {
  f->set_type(FilterKindToProto(t.kind));
  f->set_motion_model(engine::MotionModelKindName(t.kalman.motion_model));
  f->set_imm_modes(engine::ImmModesName(t.imm_modes));
  f->set_imm_variant(engine::KalmanVariantName(t.imm_variant));
  f->set_robust(engine::RobustUpdateName(t.kalman.robust));
  f->set_particles(static_cast<uint32_t>(t.particle.particles));
  // The noise the session's filter reads: the Kalman filters' for ekf, ukf and imm.
  const bool kalman = t.kind != engine::FilterKind::kPf && t.kind != engine::FilterKind::kMmpf;
  f->set_accel_noise_mps2(kalman ? t.kalman.motion.accel_noise_mps2 : t.particle.accel_noise_mps2);
  f->set_tdoa_sigma_s(kalman ? t.kalman.tdoa_sigma_s : t.particle.tdoa_sigma_s);
  f->set_likelihood(t.particle.likelihood == engine::Likelihood::kGcc       ? v1::LIKELIHOOD_GCC
                    : t.particle.likelihood == engine::Likelihood::kMixture ? v1::LIKELIHOOD_MIXTURE
                                                                            : v1::LIKELIHOOD_PEAK);
  f->set_outlier_probability(t.particle.outlier_probability);
  f->set_manoeuvre_share(t.particle.manoeuvre_share);
  f->set_manoeuvre_scale(t.particle.manoeuvre_scale);
  f->set_accel_level_floor(t.particle.accel_level_floor);
  f->set_accel_level_ceiling(t.particle.accel_level_ceiling);
  // 0 on the wire means "the default": a switch rate of 0 goes out as -1.
  f->set_accel_level_switch_hz(t.particle.accel_level_switch_hz > 0.0 ? t.particle.accel_level_switch_hz : -1.0);
  // 0 on the wire means "the default": no turn rates go out as -1.
  f->set_turn_rate_max_radps(t.particle.turn_rate_max_radps > 0.0 ? t.particle.turn_rate_max_radps : -1.0);
  // Likewise: no speed changes go out as -1.
  f->set_speed_change_max_mps2(t.particle.speed_change_max_mps2 > 0.0 ? t.particle.speed_change_max_mps2 : -1.0);
  f->set_min_peak_snr(kalman ? t.kalman.min_peak_snr : t.particle.min_peak_snr);
  f->set_resample_threshold(t.particle.resample_threshold);
}

}  // namespace localizer::wire
