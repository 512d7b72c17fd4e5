// wire/config_wire: SessionConfig defaults and round trips (the multiple-model filters',
// bounds, presence, localization and direction fields included), refused names quoted, policy limits
// and bad values answered INVALID_ARGUMENT naming the field.
#include "wire/config_wire.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <optional>
#include <tuple>
#include <utility>
#include <variant>
#include <vector>

#include "tests/wire/minimal_config.h"
#include "wire/string_limits.h"

namespace localizer::wire {
namespace {

using testing::MinimalConfig;

// The audio config ConfigFromProto decodes from `p` (a failure if it decoded another kind).
StatusOr<engine::AudioSessionConfig> AudioFromProto(const v1::SessionConfig& p, const ConfigPolicy& policy) {
  auto config = ConfigFromProto(p, policy);
  if (!config.ok()) return config.status();
  EXPECT_TRUE(std::holds_alternative<engine::AudioSessionConfig>(*config));
  return std::get<engine::AudioSessionConfig>(*std::move(config));
}

TEST(ConfigWire, ZeroFieldsTakeTheEngineDefaults) {
  ConfigPolicy policy;
  policy.default_backend = "cpu";
  auto config = AudioFromProto(MinimalConfig(), policy);
  ASSERT_TRUE(config.ok()) << config.status().ToString();
  const engine::AudioSessionConfig defaults;
  EXPECT_EQ(config->frame_samples, defaults.frame_samples);
  EXPECT_EQ(config->hop_samples, defaults.frame_samples / 2);
  EXPECT_EQ(config->tracker.particle.particles, defaults.tracker.particle.particles);
  EXPECT_EQ(config->tracker.particle.accel_noise_mps2, defaults.tracker.particle.accel_noise_mps2);
  EXPECT_EQ(config->tracker.particle.min_peak_snr, defaults.tracker.particle.min_peak_snr);
  EXPECT_EQ(config->tracker.kalman.motion.accel_noise_mps2, defaults.tracker.kalman.motion.accel_noise_mps2);
  EXPECT_EQ(config->tracker.kalman.min_peak_snr, defaults.tracker.kalman.min_peak_snr);
  EXPECT_EQ(config->seed, defaults.seed);
  EXPECT_EQ(config->backend, engine::BackendChoice::kCpu);
  EXPECT_EQ(config->max_block_samples, policy.max_block_samples);
  EXPECT_FALSE(config->init_region_min_m.allFinite());
}

TEST(ConfigWire, EffectiveConfigRoundTrips) {
  v1::SessionConfig p = MinimalConfig();
  p.set_frame_samples(2048);
  p.set_hop_samples(512);
  p.set_weighting(v1::WEIGHTING_SCOT);
  p.set_band_low_hz(100.0);
  p.set_band_high_hz(9000.0);
  p.mutable_filter()->set_particles(777);
  p.mutable_filter()->set_likelihood(v1::LIKELIHOOD_GCC);
  p.set_seed(0);  // explicitly zero: kept, not defaulted
  p.mutable_init_region()->mutable_min_m()->set_x(-1.0);
  p.mutable_init_region()->mutable_max_m()->set_x(1.0);
  auto config = AudioFromProto(p, {});
  ASSERT_TRUE(config.ok()) << config.status().ToString();
  EXPECT_EQ(config->seed, 0u);
  const v1::SessionConfig effective = ConfigToProto(*config, "label");
  auto again = AudioFromProto(effective, {});
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(ConfigToProto(*again, "label").SerializeAsString(), effective.SerializeAsString());
  EXPECT_EQ(effective.filter().particles(), 777u);
  EXPECT_EQ(effective.weighting(), v1::WEIGHTING_SCOT);
  EXPECT_EQ(effective.hop_samples(), 512u);
}

// Every weighting the engine has travels both ways under its own enum value.
TEST(ConfigWire, EveryWeightingRoundTrips) {
  const std::pair<v1::Weighting, engine::Weighting> all[] = {
      {v1::WEIGHTING_PHAT, engine::Weighting::kPhat},
      {v1::WEIGHTING_PHAT_BETA, engine::Weighting::kPhatBeta},
      {v1::WEIGHTING_SCOT, engine::Weighting::kScot},
      {v1::WEIGHTING_CC, engine::Weighting::kCc},
      {v1::WEIGHTING_PHAT_COHERENCE, engine::Weighting::kPhatCoherence},
      {v1::WEIGHTING_PHAT_SHARE, engine::Weighting::kPhatShare},
  };
  for (const auto& [wire, engine_weighting] : all) {
    v1::SessionConfig p = MinimalConfig();
    p.set_weighting(wire);
    auto config = AudioFromProto(p, {});
    ASSERT_TRUE(config.ok()) << config.status().ToString();
    EXPECT_EQ(config->weighting, engine_weighting) << v1::Weighting_Name(wire);
    EXPECT_EQ(ConfigToProto(*config, "label").weighting(), wire);
  }
}

TEST(ConfigWire, MixtureLikelihoodAndItsOutlierProbabilityRoundTrip) {
  v1::SessionConfig p = MinimalConfig();
  p.mutable_filter()->set_likelihood(v1::LIKELIHOOD_MIXTURE);
  auto defaulted = AudioFromProto(p, {});
  ASSERT_TRUE(defaulted.ok()) << defaulted.status().ToString();
  EXPECT_EQ(defaulted->tracker.particle.likelihood, engine::Likelihood::kMixture);
  EXPECT_EQ(defaulted->tracker.particle.outlier_probability, 0.05);  // unset: the default
  p.mutable_filter()->set_outlier_probability(0.2);
  auto config = AudioFromProto(p, {});
  ASSERT_TRUE(config.ok());
  EXPECT_EQ(config->tracker.particle.outlier_probability, 0.2);
  const v1::SessionConfig effective = ConfigToProto(*config, "");
  EXPECT_EQ(effective.filter().likelihood(), v1::LIKELIHOOD_MIXTURE);
  EXPECT_EQ(effective.filter().outlier_probability(), 0.2);
  p.mutable_filter()->set_outlier_probability(1.0);
  auto bad = AudioFromProto(p, {});
  const Status status = bad.ok() ? (*bad).Validate() : bad.status();
  EXPECT_EQ(status.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(status.message().find("outlier_probability"), std::string::npos) << status.message();
}

TEST(ConfigWire, ManoeuvreShareZeroIsHonouredAndBadValuesAreNamed) {
  v1::SessionConfig p = MinimalConfig();
  auto defaulted = AudioFromProto(p, {});
  ASSERT_TRUE(defaulted.ok()) << defaulted.status().ToString();
  EXPECT_EQ(defaulted->tracker.particle.manoeuvre_share, engine::ParticleFilterOptions{}.manoeuvre_share);
  EXPECT_EQ(defaulted->tracker.particle.manoeuvre_scale, engine::ParticleFilterOptions{}.manoeuvre_scale);
  p.mutable_filter()->set_manoeuvre_share(0.0);  // set, and zero: plain white acceleration
  p.mutable_filter()->set_manoeuvre_scale(7.0);
  auto config = AudioFromProto(p, {});
  ASSERT_TRUE(config.ok());
  EXPECT_EQ(config->tracker.particle.manoeuvre_share, 0.0);
  EXPECT_EQ(config->tracker.particle.manoeuvre_scale, 7.0);
  const v1::SessionConfig effective = ConfigToProto(*config, "");
  EXPECT_TRUE(effective.filter().has_manoeuvre_share());
  EXPECT_EQ(effective.filter().manoeuvre_share(), 0.0);
  EXPECT_EQ(effective.filter().manoeuvre_scale(), 7.0);
  for (const auto& [share, scale, field] :
       {std::tuple{1.0, 4.0, "filter.manoeuvre_share"}, std::tuple{0.1, 0.5, "filter.manoeuvre_scale"}}) {
    p.mutable_filter()->set_manoeuvre_share(share);
    p.mutable_filter()->set_manoeuvre_scale(scale);
    auto bad = AudioFromProto(p, {});
    const Status status = bad.ok() ? (*bad).Validate() : bad.status();
    EXPECT_EQ(status.code(), StatusCode::kInvalidArgument) << field;
    EXPECT_NE(status.message().find(field), std::string::npos) << status.message();
  }
}

TEST(ConfigWire, AccelerationLevelsDefaultRoundTripAndAreValidated) {
  v1::SessionConfig p = MinimalConfig();
  const engine::ParticleFilterOptions engine_default;
  auto defaulted = AudioFromProto(p, {});
  ASSERT_TRUE(defaulted.ok()) << defaulted.status().ToString();
  EXPECT_EQ(defaulted->tracker.particle.accel_level_floor, engine_default.accel_level_floor);
  EXPECT_EQ(defaulted->tracker.particle.accel_level_ceiling, engine_default.accel_level_ceiling);
  EXPECT_EQ(defaulted->tracker.particle.accel_level_switch_hz, engine_default.accel_level_switch_hz);
  p.mutable_filter()->set_accel_level_floor(0.01);
  p.mutable_filter()->set_accel_level_ceiling(5.0);
  p.mutable_filter()->set_accel_level_switch_hz(-1.0);  // negative: a rate of 0 (levels never redrawn)
  p.mutable_filter()->set_turn_rate_max_radps(0.8);
  p.mutable_filter()->set_speed_change_max_mps2(1.5);
  auto config = AudioFromProto(p, {});
  ASSERT_TRUE(config.ok()) << config.status().ToString();
  EXPECT_EQ(config->tracker.particle.accel_level_floor, 0.01);
  EXPECT_EQ(config->tracker.particle.accel_level_ceiling, 5.0);
  EXPECT_EQ(config->tracker.particle.accel_level_switch_hz, 0.0);
  const v1::SessionConfig effective = ConfigToProto(*config, "");
  auto again = AudioFromProto(effective, {});
  ASSERT_TRUE(again.ok()) << again.status().ToString();
  EXPECT_EQ(again->tracker.particle.accel_level_floor, 0.01);
  EXPECT_EQ(again->tracker.particle.accel_level_ceiling, 5.0);
  EXPECT_EQ(again->tracker.particle.accel_level_switch_hz, 0.0);
  EXPECT_EQ(again->tracker.particle.turn_rate_max_radps, 0.8);
  EXPECT_EQ(again->tracker.particle.speed_change_max_mps2, 1.5);
  EXPECT_EQ(defaulted->tracker.particle.turn_rate_max_radps, engine_default.turn_rate_max_radps);
  EXPECT_EQ(defaulted->tracker.particle.speed_change_max_mps2, engine_default.speed_change_max_mps2);
  p.mutable_filter()->set_turn_rate_max_radps(-1.0);  // negative: no turn rates
  auto no_turns = AudioFromProto(p, {});
  ASSERT_TRUE(no_turns.ok()) << no_turns.status().ToString();
  EXPECT_EQ(no_turns->tracker.particle.turn_rate_max_radps, 0.0);
  auto no_turns_again = AudioFromProto(ConfigToProto(*no_turns, ""), {});
  ASSERT_TRUE(no_turns_again.ok());
  EXPECT_EQ(no_turns_again->tracker.particle.turn_rate_max_radps, 0.0) << "off survives the round trip";
  p.mutable_filter()->set_speed_change_max_mps2(-1.0);  // negative: no speed changes
  auto no_speed_changes = AudioFromProto(p, {});
  ASSERT_TRUE(no_speed_changes.ok()) << no_speed_changes.status().ToString();
  EXPECT_EQ(no_speed_changes->tracker.particle.speed_change_max_mps2, 0.0);
  auto no_speed_changes_again = AudioFromProto(ConfigToProto(*no_speed_changes, ""), {});
  ASSERT_TRUE(no_speed_changes_again.ok());
  EXPECT_EQ(no_speed_changes_again->tracker.particle.speed_change_max_mps2, 0.0) << "off survives the round trip";
  p.mutable_filter()->set_accel_level_floor(6.0);  // above the ceiling (5)
  auto bad = AudioFromProto(p, {});
  const Status status = bad.ok() ? (*bad).Validate() : bad.status();
  EXPECT_EQ(status.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(status.message().find("filter.accel_level_floor"), std::string::npos) << status.message();
}

TEST(ConfigWire, FilterTypeAndMotionModelRoundTrip) {
  v1::SessionConfig p = MinimalConfig();
  p.mutable_filter()->set_type(v1::FILTER_TYPE_UKF);
  p.mutable_filter()->set_motion_model("singer");
  auto config = AudioFromProto(p, {});
  ASSERT_TRUE(config.ok()) << config.status().ToString();
  EXPECT_EQ(config->tracker.kind, engine::FilterKind::kUkf);
  EXPECT_EQ(config->tracker.kalman.motion_model, engine::MotionModelKind::kSinger);
  const v1::SessionConfig effective = ConfigToProto(*config, "");
  EXPECT_EQ(effective.filter().type(), v1::FILTER_TYPE_UKF);
  EXPECT_EQ(effective.filter().motion_model(), "singer");
  // Defaults: the particle filter with constant velocity.
  auto plain = AudioFromProto(MinimalConfig(), {});
  ASSERT_TRUE(plain.ok());
  EXPECT_EQ(plain->tracker.kind, engine::FilterKind::kPf);
  EXPECT_EQ(ConfigToProto(*plain, "").filter().motion_model(), "cv");
  // The particle filter has no turn model; an unknown model is named.
  p.mutable_filter()->set_type(v1::FILTER_TYPE_PF);
  p.mutable_filter()->set_motion_model("ct");
  EXPECT_EQ(AudioFromProto(p, {}).status().code(), StatusCode::kInvalidArgument);
  p.mutable_filter()->set_type(v1::FILTER_TYPE_EKF);
  p.mutable_filter()->set_motion_model("bicycle");
  EXPECT_NE(AudioFromProto(p, {}).status().message().find("bicycle"), std::string::npos);
  p.mutable_filter()->set_motion_model("cv");
  p.mutable_filter()->set_type(static_cast<v1::FilterType>(42));
  EXPECT_EQ(AudioFromProto(p, {}).status().code(), StatusCode::kInvalidArgument);
}

TEST(ConfigWire, MultipleModelFiltersAndTheirFieldsRoundTrip) {
  v1::SessionConfig p = MinimalConfig();
  p.mutable_filter()->set_type(v1::FILTER_TYPE_IMM);
  p.mutable_filter()->set_imm_modes("cv,ca");
  p.mutable_filter()->set_imm_variant("ukf");
  p.mutable_filter()->set_robust("huber");
  auto config = AudioFromProto(p, {});
  ASSERT_TRUE(config.ok()) << config.status().ToString();
  EXPECT_EQ(config->tracker.kind, engine::FilterKind::kImm);
  EXPECT_EQ(config->tracker.imm_modes,
            (std::vector<engine::MotionModelKind>{engine::MotionModelKind::kCv, engine::MotionModelKind::kCa}));
  EXPECT_EQ(config->tracker.imm_variant, engine::KalmanVariant::kUnscented);
  EXPECT_EQ(config->tracker.kalman.robust, engine::RobustUpdate::kHuber);
  const v1::SessionConfig effective = ConfigToProto(*config, "");
  EXPECT_EQ(effective.filter().type(), v1::FILTER_TYPE_IMM);
  EXPECT_EQ(effective.filter().imm_modes(), "cv,ca");
  EXPECT_EQ(effective.filter().imm_variant(), "ukf");
  EXPECT_EQ(effective.filter().robust(), "huber");
  // Unset fields take the engine defaults and are reported.
  v1::SessionConfig mmpf = MinimalConfig();
  mmpf.mutable_filter()->set_type(v1::FILTER_TYPE_MMPF);
  auto plain = AudioFromProto(mmpf, {});
  ASSERT_TRUE(plain.ok()) << plain.status().ToString();
  EXPECT_EQ(plain->tracker.kind, engine::FilterKind::kMmpf);
  const v1::SessionConfig reported = ConfigToProto(*plain, "");
  EXPECT_EQ(reported.filter().type(), v1::FILTER_TYPE_MMPF);
  EXPECT_EQ(reported.filter().imm_modes(), "cv,ct");
  EXPECT_EQ(reported.filter().imm_variant(), "ekf");
  EXPECT_EQ(reported.filter().robust(), "none");
  // Bad values name the proto field.
  p.mutable_filter()->set_imm_modes("cv,warp");
  EXPECT_NE(AudioFromProto(p, {}).status().message().find("filter.imm_modes"), std::string::npos);
  p.mutable_filter()->set_imm_modes("");
  p.mutable_filter()->set_robust("tukey");
  EXPECT_NE(AudioFromProto(p, {}).status().message().find("filter.robust"), std::string::npos);
}

// Found by fuzz_session_config: the engine's name parsers quote the refused name as sent, so
// a NUL, newline or DEL in filter.robust (or any name field) went back to the client and into
// the log unescaped. Every such refusal is printable ASCII and still names the field.
TEST(ConfigWire, RefusedNamesAreQuotedEscaped) {
  const std::string bad("h\0\n\x7f\xff", 5);
  const auto check = [&](const v1::SessionConfig& p, const std::string& field) {
    const Status status = ConfigFromProto(p, {}).status();
    ASSERT_FALSE(status.ok()) << field;
    EXPECT_EQ(status.code(), StatusCode::kInvalidArgument) << field;
    EXPECT_NE(status.message().find(field), std::string::npos) << status.message();
    for (const char ch : status.message()) {
      const auto u = static_cast<unsigned char>(ch);
      EXPECT_TRUE(u >= 0x20 && u < 0x7f) << field << ": raw byte " << int{u} << " in " << status.message();
    }
    EXPECT_NE(status.message().find("h\\x00\\x0a\\x7f\\xff"), std::string::npos) << status.message();
  };
  v1::SessionConfig p = MinimalConfig();
  p.mutable_filter()->set_robust(bad);
  check(p, "filter.robust");
  p = MinimalConfig();
  p.mutable_filter()->set_type(v1::FILTER_TYPE_EKF);
  p.mutable_filter()->set_motion_model(bad);
  check(p, "filter.motion_model");
  p = MinimalConfig();
  p.mutable_filter()->set_imm_modes("cv," + bad);
  check(p, "filter.imm_modes");
  p = MinimalConfig();
  p.mutable_filter()->set_imm_variant(bad);
  check(p, "filter.imm_variant");
  p = MinimalConfig();
  p.set_backend(bad);
  check(p, "backend");
  p = MinimalConfig();
  p.mutable_platform()->set_attitude_filter(bad);
  check(p, "platform.attitude_filter");
  EXPECT_EQ(EscapeUnprintable("a 'b\"c\\' \x01\xc3\xa9"), "a 'b\"c\\' \\x01\\xc3\\xa9");
}

TEST(ConfigWire, PolicyLimitsAreInvalidArgumentNamingTheField) {
  ConfigPolicy policy;
  policy.max_particles = 1000;
  policy.max_channels = 4;
  v1::SessionConfig p = MinimalConfig();
  p.mutable_filter()->set_particles(1001);
  auto config = AudioFromProto(p, policy);
  EXPECT_EQ(config.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(config.status().message().find("filter.particles"), std::string::npos);
  p = MinimalConfig();
  *p.mutable_array()->add_sensors_m() = p.array().sensors_m(1);
  EXPECT_NE(AudioFromProto(p, policy).status().message().find("array.sensors_m"), std::string::npos);
  p = MinimalConfig();
  p.mutable_array()->clear_sound_speed_mps();
  EXPECT_NE(AudioFromProto(p, policy).status().message().find("array.sound_speed_mps"), std::string::npos);
  p = MinimalConfig();
  p.clear_array();
  EXPECT_NE(AudioFromProto(p, policy).status().message().find("array"), std::string::npos);
}

TEST(ConfigWire, BoundsAndPresenceFieldsDefaultWhenUnset) {
  auto config = AudioFromProto(MinimalConfig(), {});
  ASSERT_TRUE(config.ok()) << config.status().ToString();
  const engine::AudioSessionConfig defaults;
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(config->bounds_min_m(i), -std::numeric_limits<double>::infinity());
    EXPECT_EQ(config->bounds_max_m(i), std::numeric_limits<double>::infinity());
  }
  EXPECT_EQ(config->search_radius_m, 0.0);
  EXPECT_EQ(config->presence_false_alarm, defaults.presence_false_alarm);
  EXPECT_EQ(config->source_timeout_s, defaults.source_timeout_s);
  // effective_config: no bounds (unbounded), the defaults written out.
  const v1::SessionConfig effective = ConfigToProto(*config, "");
  EXPECT_FALSE(effective.has_bounds());
  EXPECT_EQ(effective.search_radius_m(), 0.0);
  EXPECT_EQ(effective.presence_false_alarm(), 1e-3);
  EXPECT_EQ(effective.source_timeout_s(), 2.0);
}

TEST(ConfigWire, WaterColumnBoundsAndPresenceFieldsRoundTrip) {
  v1::SessionConfig p = MinimalConfig();
  p.mutable_bounds()->set_max_z_m(0.0);   // the surface: explicitly zero, kept
  p.mutable_bounds()->set_min_z_m(-8.0);  // the bottom
  p.mutable_bounds()->set_min_x_m(-50.0);
  p.mutable_bounds()->set_max_y_m(std::numeric_limits<double>::infinity());  // open, as unset
  p.set_search_radius_m(30.0);
  p.set_presence_false_alarm(0.01);
  p.set_source_timeout_s(5.0);
  auto config = AudioFromProto(p, {});
  ASSERT_TRUE(config.ok()) << config.status().ToString();
  EXPECT_EQ(config->bounds_max_m.z(), 0.0);
  EXPECT_EQ(config->bounds_min_m.z(), -8.0);
  EXPECT_EQ(config->bounds_min_m.x(), -50.0);
  EXPECT_EQ(config->bounds_max_m.x(), std::numeric_limits<double>::infinity());
  EXPECT_EQ(config->bounds_min_m.y(), -std::numeric_limits<double>::infinity());
  EXPECT_EQ(config->bounds_max_m.y(), std::numeric_limits<double>::infinity());
  EXPECT_EQ(config->search_radius_m, 30.0);
  EXPECT_EQ(config->presence_false_alarm, 0.01);
  EXPECT_EQ(config->source_timeout_s, 5.0);
  const v1::SessionConfig effective = ConfigToProto(*config, "");
  ASSERT_TRUE(effective.has_bounds());
  EXPECT_TRUE(effective.bounds().has_max_z_m());
  EXPECT_EQ(effective.bounds().max_z_m(), 0.0);
  EXPECT_EQ(effective.bounds().min_z_m(), -8.0);
  EXPECT_EQ(effective.bounds().min_x_m(), -50.0);
  EXPECT_FALSE(effective.bounds().has_max_x_m());  // open sides stay unset
  EXPECT_FALSE(effective.bounds().has_min_y_m());
  EXPECT_FALSE(effective.bounds().has_max_y_m());
  EXPECT_EQ(effective.search_radius_m(), 30.0);
  EXPECT_EQ(effective.presence_false_alarm(), 0.01);
  EXPECT_EQ(effective.source_timeout_s(), 5.0);
  auto again = AudioFromProto(effective, {});
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(ConfigToProto(*again, "").SerializeAsString(), effective.SerializeAsString());
}

TEST(ConfigWire, BadBoundsAndPresenceFieldsAreInvalidArgumentNamingTheField) {
  const auto refused = [](const v1::SessionConfig& p, const std::string& field) {
    auto config = AudioFromProto(p, {});
    ASSERT_FALSE(config.ok()) << field;
    EXPECT_EQ(config.status().code(), StatusCode::kInvalidArgument) << config.status().ToString();
    EXPECT_NE(config.status().message().find(field), std::string::npos) << config.status().message();
  };
  v1::SessionConfig p = MinimalConfig();
  p.mutable_bounds()->set_min_z_m(0.0);
  p.mutable_bounds()->set_max_z_m(-8.0);  // bottom above the surface
  refused(p, "bounds.min_z_m");
  p = MinimalConfig();
  p.mutable_bounds()->set_min_y_m(3.0);
  p.mutable_bounds()->set_max_y_m(3.0);  // empty
  refused(p, "bounds.min_y_m");
  p = MinimalConfig();
  p.mutable_bounds()->set_max_x_m(std::nan(""));
  refused(p, "bounds.max_x_m");
  p = MinimalConfig();
  p.mutable_bounds()->set_min_x_m(std::numeric_limits<double>::infinity());  // +inf is no lower side
  refused(p, "bounds.min_x_m");
  p = MinimalConfig();
  p.mutable_bounds()->set_max_z_m(-std::numeric_limits<double>::infinity());
  refused(p, "bounds.max_z_m");
  p = MinimalConfig();
  p.mutable_bounds()->set_min_y_m(-2e7);
  refused(p, "bounds.min_y_m");
  p = MinimalConfig();
  p.set_search_radius_m(-1.0);
  refused(p, "search_radius_m");
  p = MinimalConfig();
  p.set_presence_false_alarm(0.5);
  refused(p, "presence_false_alarm");
  p = MinimalConfig();
  p.set_presence_false_alarm(-1e-3);
  refused(p, "presence_false_alarm");
  p = MinimalConfig();
  p.set_source_timeout_s(-2.0);
  refused(p, "source_timeout_s");
  p = MinimalConfig();
  p.set_source_timeout_s(std::nan(""));
  refused(p, "source_timeout_s");
}

TEST(ConfigWire, LocalizationFieldsRoundTripAndBadOnesAreNamed) {
  v1::SessionConfig p = MinimalConfig();
  auto config = AudioFromProto(p, {});
  ASSERT_TRUE(config.ok());
  EXPECT_EQ(config->localization, engine::Localization::kAuto);
  EXPECT_EQ(config->max_sources, 0);  // not stated
  EXPECT_EQ(config->EffectiveMaxSources(), 4);
  EXPECT_FALSE(ConfigToProto(*config, "").has_max_sources());  // echoed only when stated
  EXPECT_TRUE(config->source_side.isZero());
  p.set_localization("direction");
  p.set_max_sources(2);
  p.mutable_source_side()->set_z(1.0);
  config = AudioFromProto(p, {});
  ASSERT_TRUE(config.ok()) << config.status().ToString();
  EXPECT_EQ(config->localization, engine::Localization::kDirection);
  EXPECT_EQ(config->max_sources, 2);
  EXPECT_EQ(config->source_side, engine::Vec3::UnitZ());
  const v1::SessionConfig effective = ConfigToProto(*config, "");
  EXPECT_EQ(effective.localization(), "direction");
  EXPECT_EQ(effective.max_sources(), 2u);
  EXPECT_EQ(effective.source_side().z(), 1.0);
  p.set_localization("sideways");
  EXPECT_NE(AudioFromProto(p, {}).status().message().find("localization 'sideways'"), std::string::npos);
  p.set_localization("auto");
  p.set_max_sources(0);
  EXPECT_NE(AudioFromProto(p, {}).status().message().find("max_sources is 0"), std::string::npos);
  p.set_max_sources(3);
  p.mutable_source_side()->set_x(std::numeric_limits<double>::infinity());
  EXPECT_NE(AudioFromProto(p, {}).status().message().find("source_side"), std::string::npos);
}

TEST(ConfigWire, SourcePlaneRoundTripsAndAZeroNormalIsNamed) {
  v1::SessionConfig p = MinimalConfig();
  auto config = AudioFromProto(p, {});
  ASSERT_TRUE(config.ok());
  EXPECT_TRUE(config->source_plane_normal.isZero());
  EXPECT_FALSE(ConfigToProto(*config, "").has_source_plane());
  p.mutable_source_plane()->mutable_point_m()->set_z(1.5);
  p.mutable_source_plane()->mutable_normal()->set_z(2.0);
  config = AudioFromProto(p, {});
  ASSERT_TRUE(config.ok()) << config.status().ToString();
  EXPECT_EQ(config->source_plane_point_m, engine::Vec3(0, 0, 1.5));
  EXPECT_EQ(config->source_plane_normal, engine::Vec3(0, 0, 2.0));
  const v1::SessionConfig effective = ConfigToProto(*config, "");
  EXPECT_EQ(effective.source_plane().point_m().z(), 1.5);
  EXPECT_EQ(effective.source_plane().normal().z(), 2.0);
  p.mutable_source_plane()->mutable_normal()->set_z(0.0);
  EXPECT_NE(AudioFromProto(p, {}).status().message().find("source_plane.normal must not be zero"), std::string::npos);
  p.mutable_source_plane()->mutable_normal()->set_z(1.0);
  p.mutable_source_plane()->mutable_point_m()->set_y(std::numeric_limits<double>::quiet_NaN());
  EXPECT_NE(AudioFromProto(p, {}).status().message().find("source_plane"), std::string::npos);
}

TEST(ConfigWire, DirectionWeightingAndHoldRoundTripAndABadHoldIsNamed) {
  v1::SessionConfig p = MinimalConfig();
  auto config = AudioFromProto(p, {});
  ASSERT_TRUE(config.ok());
  const engine::AudioSessionConfig defaults;
  EXPECT_EQ(config->direction_present_hold_s, defaults.direction_present_hold_s);  // unset: the engine's
  EXPECT_TRUE(config->direction_diffuse_weighting);
  EXPECT_FALSE(config->direction_signal_weighting.has_value());  // unset: by the array's shape
  EXPECT_FALSE(ConfigToProto(*config, "").has_direction_signal_weighting());
  p.set_direction_present_hold_s(0.0);  // stated 0 is honoured, not read as "unset"
  p.set_direction_diffuse_weighting(false);
  p.set_direction_signal_weighting(false);
  config = AudioFromProto(p, {});
  ASSERT_TRUE(config.ok()) << config.status().ToString();
  EXPECT_EQ(config->direction_present_hold_s, 0.0);
  EXPECT_FALSE(config->direction_diffuse_weighting);
  EXPECT_EQ(config->direction_signal_weighting, std::optional<bool>(false));
  const v1::SessionConfig effective = ConfigToProto(*config, "");
  EXPECT_TRUE(effective.has_direction_present_hold_s());
  EXPECT_EQ(effective.direction_present_hold_s(), 0.0);
  EXPECT_FALSE(effective.direction_diffuse_weighting());
  EXPECT_TRUE(effective.has_direction_signal_weighting());
  EXPECT_FALSE(effective.direction_signal_weighting());
  p.set_direction_present_hold_s(2.0);
  EXPECT_NE(AudioFromProto(p, {}).status().message().find("direction_present_hold_s"), std::string::npos);
}

}  // namespace
}  // namespace localizer::wire
