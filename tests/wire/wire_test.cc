// wire/: frame-major <-> channel-major blocks (float and 16-bit PCM), the rules a
// bad block breaks, config defaults and round trips (the multiple-model filters' fields
// included), estimates with model probabilities both ways, Locate's request and response,
// Status -> gRPC codes.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <tuple>
#include <variant>
#include <vector>

#include "wire/block_wire.h"
#include "wire/config_wire.h"
#include "wire/estimate_wire.h"
#include "wire/imu_wire.h"
#include "wire/locate_wire.h"
#include "wire/status_wire.h"
#include "wire/string_limits.h"

namespace localizer::wire {
namespace {

v1::SampleBlock InterleavedBlock(int channels, int frames) {
  v1::SampleBlock block;
  block.set_sequence(7);
  block.set_channel_count(static_cast<uint32_t>(channels));
  for (int i = 0; i < frames; ++i) {
    for (int c = 0; c < channels; ++c) block.add_samples(static_cast<float>(100 * c + i));
  }
  return block;
}

TEST(BlockWire, DecodeDeinterleavesToChannelMajor) {
  DecodedBlock out;
  std::string reason;
  ASSERT_TRUE(DecodeBlock(InterleavedBlock(4, 5), {4, 1000}, &out, &reason).ok());
  EXPECT_EQ(out.view.sequence, 7u);
  EXPECT_EQ(out.view.channel_count, 4);
  EXPECT_EQ(out.view.samples_per_channel, 5);
  for (int c = 0; c < 4; ++c) {
    for (int i = 0; i < 5; ++i) EXPECT_EQ(out.view.samples[c * 5 + i], static_cast<float>(100 * c + i));
  }
}

TEST(BlockWire, EncodeThenDecodeIsIdentityForFloats) {
  std::vector<float> channel_major(3 * 8);
  for (size_t i = 0; i < channel_major.size(); ++i) channel_major[i] = std::sin(0.37f * static_cast<float>(i));
  v1::SampleBlock block;
  EncodeBlock({9, 3, 8, channel_major.data()}, false, &block);
  EXPECT_EQ(block.samples(1), channel_major[8]);  // frame 0, channel 1
  DecodedBlock out;
  std::string reason;
  ASSERT_TRUE(DecodeBlock(block, {3, 8}, &out, &reason).ok());
  EXPECT_EQ(out.samples, channel_major);
}

TEST(BlockWire, Pcm16IsLittleEndianOver32768AndClips) {
  const std::vector<float> channel_major = {0.5f, -1.0f, 2.0f, -0.25f};  // 2 channels x 2 samples
  v1::SampleBlock block;
  EncodeBlock({1, 2, 2, channel_major.data()}, true, &block);
  ASSERT_EQ(block.pcm_s16le().size(), 8u);
  EXPECT_EQ(block.samples_size(), 0);
  // Frame 0: ch0 0.5 -> 16384 = 0x4000, ch1 2.0 clips to 32767 = 0x7fff.
  EXPECT_EQ(static_cast<unsigned char>(block.pcm_s16le()[0]), 0x00);
  EXPECT_EQ(static_cast<unsigned char>(block.pcm_s16le()[1]), 0x40);
  EXPECT_EQ(static_cast<unsigned char>(block.pcm_s16le()[2]), 0xff);
  EXPECT_EQ(static_cast<unsigned char>(block.pcm_s16le()[3]), 0x7f);
  DecodedBlock out;
  std::string reason;
  ASSERT_TRUE(DecodeBlock(block, {2, 2}, &out, &reason).ok());
  EXPECT_EQ(out.samples[0], 0.5f);
  EXPECT_EQ(out.samples[1], -1.0f);
  EXPECT_EQ(out.samples[2], 32767.0f / 32768.0f);
  EXPECT_EQ(out.samples[3], -0.25f);
}

TEST(BlockWire, EachBrokenRuleHasItsReason) {
  DecodedBlock out;
  std::string reason;
  v1::SampleBlock block = InterleavedBlock(4, 5);
  block.set_channel_count(3);
  EXPECT_EQ(DecodeBlock(block, {4, 1000}, &out, &reason).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(reason, "channel_count");
  // Zero channels against limits of zero channels (a session that takes no samples): a
  // rejection, not a division by zero.
  block = InterleavedBlock(4, 5);
  block.set_channel_count(0);
  EXPECT_EQ(DecodeBlock(block, {0, 0}, &out, &reason).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(reason, "channel_count");

  block = InterleavedBlock(4, 5);
  block.add_samples(1.0f);
  EXPECT_FALSE(DecodeBlock(block, {4, 1000}, &out, &reason).ok());
  EXPECT_EQ(reason, "bad_samples");

  block = InterleavedBlock(4, 5);
  block.set_pcm_s16le(std::string(40, '\0'));
  EXPECT_FALSE(DecodeBlock(block, {4, 1000}, &out, &reason).ok());
  EXPECT_EQ(reason, "bad_samples");

  block = InterleavedBlock(4, 5);
  block.set_samples(13, INFINITY);
  const Status status = DecodeBlock(block, {4, 1000}, &out, &reason);
  EXPECT_EQ(reason, "non_finite");
  EXPECT_NE(status.message().find("samples[13] (frame 3, channel 1)"), std::string::npos) << status.message();

  EXPECT_FALSE(DecodeBlock(InterleavedBlock(4, 5), {4, 4}, &out, &reason).ok());
  EXPECT_EQ(reason, "oversize");

  block = InterleavedBlock(4, 0);
  EXPECT_FALSE(DecodeBlock(block, {4, 1000}, &out, &reason).ok());
  EXPECT_EQ(reason, "empty");
}

v1::SessionConfig MinimalConfig() {
  v1::SessionConfig c;
  const double sensors[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (const auto& s : sensors) {
    v1::Vector3* v = c.mutable_array()->add_sensors_m();
    v->set_x(s[0]);
    v->set_y(s[1]);
    v->set_z(s[2]);
  }
  c.mutable_array()->set_sound_speed_mps(1500.0);
  c.set_sample_rate_hz(48000.0);
  return c;
}

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

TEST(EstimateWire, ModelProbabilitiesRoundTrip) {
  const engine::ArrayGeometry array =
      *engine::ArrayGeometry::Create({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, 1500.0);
  engine::Estimate e;
  e.frame_index = 4;
  e.initialised = true;
  e.state << 1, 2, 3, 0.1, 0.2, 0.3;
  e.model_probabilities = {{"cv", 0.25}, {"ct", 0.75}};
  v1::Estimate wire;
  EstimateToProto(e, array.reference_sensor(), "cpu", &wire);
  ASSERT_EQ(wire.model_probabilities_size(), 2);
  EXPECT_EQ(wire.model_probabilities(1).model(), "ct");
  EXPECT_EQ(wire.model_probabilities(1).probability(), 0.75);
  // A reused message is refilled, not appended to.
  EstimateToProto(e, array.reference_sensor(), "cpu", &wire);
  EXPECT_EQ(wire.model_probabilities_size(), 2);
  const engine::Estimate back = EstimateFromProto(wire);
  ASSERT_EQ(back.model_probabilities.size(), 2u);
  EXPECT_EQ(back.model_probabilities[0].model, "cv");
  EXPECT_EQ(back.model_probabilities[0].probability, 0.25);
  EXPECT_EQ(back.state, e.state);
  // Single-model filters: no entries on the wire.
  e.model_probabilities.clear();
  EstimateToProto(e, array.reference_sensor(), "cpu", &wire);
  EXPECT_EQ(wire.model_probabilities_size(), 0);
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

TEST(EstimateWire, PresenceAmbiguityAndRangeRoundTrip) {
  const engine::ArrayGeometry array =
      *engine::ArrayGeometry::Create({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, 1500.0);
  engine::Estimate e;
  e.initialised = true;
  e.source_present = true;
  e.presence_statistic = 12.5;
  e.presence_threshold = 4.25;
  e.ambiguous = true;
  e.modes = 2;
  e.far_field = true;
  e.range_sd_m = 7.5;
  v1::Estimate wire;
  EstimateToProto(e, array.reference_sensor(), "cpu", &wire);
  EXPECT_TRUE(wire.far_field());
  EXPECT_EQ(wire.range_sd_m(), 7.5);
  EXPECT_TRUE(wire.source_present());
  EXPECT_EQ(wire.presence_statistic(), 12.5);
  EXPECT_EQ(wire.presence_threshold(), 4.25);
  EXPECT_TRUE(wire.ambiguous());
  EXPECT_EQ(wire.modes(), 2u);
  engine::Estimate back = EstimateFromProto(wire);
  EXPECT_TRUE(back.source_present);
  EXPECT_EQ(back.presence_statistic, 12.5);
  EXPECT_EQ(back.presence_threshold, 4.25);
  EXPECT_TRUE(back.ambiguous);
  EXPECT_EQ(back.modes, 2);
  EXPECT_TRUE(back.far_field);
  EXPECT_EQ(back.range_sd_m, 7.5);
  // A silent, uninitialised frame: all false / zero, and a reused message is overwritten.
  engine::Estimate silent;
  silent.presence_statistic = 1.5;
  silent.presence_threshold = 4.25;
  EstimateToProto(silent, array.reference_sensor(), "cpu", &wire);
  EXPECT_FALSE(wire.source_present());
  EXPECT_FALSE(wire.ambiguous());
  EXPECT_EQ(wire.modes(), 0u);
  EXPECT_FALSE(wire.far_field());
  EXPECT_EQ(wire.range_sd_m(), 0.0);
  back = EstimateFromProto(wire);
  EXPECT_FALSE(back.source_present);
  EXPECT_EQ(back.presence_statistic, 1.5);
  EXPECT_EQ(back.modes, 0);
}

// Direction sessions: the config fields round-trip, bad values are named, and an
// estimate's sources survive the wire (NaN where the array cannot observe).
TEST(ConfigWire, LocalizationFieldsRoundTripAndBadOnesAreNamed) {
  v1::SessionConfig p = MinimalConfig();
  auto config = AudioFromProto(p, {});
  ASSERT_TRUE(config.ok());
  EXPECT_EQ(config->localization, engine::Localization::kAuto);
  EXPECT_EQ(config->max_sources, 4);
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

TEST(EstimateWire, SourcesRoundTrip) {
  engine::Estimate e;
  e.source_present = true;
  engine::SourceEstimate a;
  a.source_id = 3;
  a.status = engine::TrackStatus::kCoasting;
  a.direction = engine::Vec3(0.6, 0.8, 0.0);
  a.azimuth_rad = 0.927;
  a.elevation_rad = 0.0;
  a.sigma_rad = 0.02;
  engine::SourceEstimate line;  // a linear array's: the cone angle only
  line.source_id = 4;
  line.status = engine::TrackStatus::kConfirmed;
  line.cone_angle_rad = 1.2;
  line.source_present = true;
  line.power_db = 9.5;
  e.sources = {a, line};
  v1::Estimate wire;
  EstimateToProto(e, 0, "cpu", &wire);
  ASSERT_EQ(wire.sources_size(), 2);
  EXPECT_EQ(wire.sources(0).status(), v1::TRACK_STATUS_COASTING);
  EXPECT_EQ(wire.sources(1).status(), v1::TRACK_STATUS_CONFIRMED);
  const engine::Estimate back = EstimateFromProto(wire);
  ASSERT_EQ(back.sources.size(), 2u);
  EXPECT_EQ(back.sources[0].source_id, 3u);
  EXPECT_EQ(back.sources[0].status, engine::TrackStatus::kCoasting);
  EXPECT_EQ(back.sources[0].direction, a.direction);
  EXPECT_DOUBLE_EQ(back.sources[0].azimuth_rad, 0.927);
  EXPECT_TRUE(std::isnan(back.sources[0].power_db));
  EXPECT_FALSE(back.sources[0].source_present);
  EXPECT_TRUE(std::isnan(back.sources[1].azimuth_rad));
  EXPECT_DOUBLE_EQ(back.sources[1].cone_angle_rad, 1.2);
  EXPECT_DOUBLE_EQ(back.sources[1].power_db, 9.5);
  // A reused message is overwritten, not appended to.
  EstimateToProto(engine::Estimate{}, 0, "cpu", &wire);
  EXPECT_EQ(wire.sources_size(), 0);
}

TEST(ImuWire, ABatchAboveTheSampleLimitIsInvalidArgumentNamingIt) {
  std::vector<engine::ImuSample> samples(kMaxImuSamplesPerBatch + 1);
  for (size_t i = 0; i < samples.size(); ++i) samples[i].t_s = 1e-3 * static_cast<double>(i + 1);
  v1::ImuBatch batch;
  EncodeImuBatch(samples, nullptr, 1, &batch);
  const auto refused = DecodeImuBatch(batch);
  EXPECT_EQ(refused.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(refused.status().message().find("imu.samples"), std::string::npos) << refused.status().message();
  samples.pop_back();
  EncodeImuBatch(samples, nullptr, 1, &batch);
  EXPECT_TRUE(DecodeImuBatch(batch).ok());
}

TEST(StatusWire, CodesMapByName) {
  for (StatusCode code : {StatusCode::kInvalidArgument, StatusCode::kFailedPrecondition, StatusCode::kOutOfRange,
                          StatusCode::kNotFound, StatusCode::kUnavailable, StatusCode::kInternal,
                          StatusCode::kPermissionDenied, StatusCode::kResourceExhausted, StatusCode::kCancelled}) {
    const grpc::Status g = ToGrpcStatus(Status(code, "m"));
    EXPECT_STREQ(GrpcCodeName(g.error_code()), StatusCodeName(code));
    EXPECT_EQ(g.error_message(), "m");
  }
  EXPECT_TRUE(ToGrpcStatus(Status::Ok()).ok());
}

TEST(LocateWire, DetectionConfigsAndBadBlocksAreInvalidArgumentNamingTheField) {
  v1::LocateRequest request;
  request.mutable_config()->mutable_detections();
  DecodedLocate decoded;
  Status status = DecodeLocateRequest(request, ConfigPolicy{}, &decoded);
  EXPECT_EQ(status.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(status.message().find("config.detections"), std::string::npos) << status.message();

  *request.mutable_config() = MinimalConfig();
  *request.mutable_block() = InterleavedBlock(3, 100);  // the array has 4 sensors
  status = DecodeLocateRequest(request, ConfigPolicy{}, &decoded);
  EXPECT_EQ(status.code(), StatusCode::kInvalidArgument);

  *request.mutable_block() = InterleavedBlock(4, 100);
  ASSERT_TRUE(DecodeLocateRequest(request, ConfigPolicy{}, &decoded).ok());
  EXPECT_EQ(decoded.config.sensors_m.size(), 4u);
  EXPECT_EQ(decoded.block.view.channel_count, 4);
  EXPECT_EQ(decoded.block.view.samples_per_channel, 100);
  EXPECT_EQ(decoded.block.view.samples[100], 100.0f);  // channel 1, sample 0
}

TEST(LocateWire, ResultFillsPairsFixAndCovariance) {
  // Reference sensor 1: pairs are (1, 0), (1, 2), (1, 3).
  const std::vector<engine::Vec3> sensors = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  auto array = engine::ArrayGeometry::Create(sensors, 1500.0, 1);
  ASSERT_TRUE(array.ok()) << array.status().ToString();
  engine::LocateResult result;
  for (int p = 0; p < 3; ++p) {
    engine::PairMeasurement m;
    m.delay_s = 1e-4 * (p + 1);
    m.quality = 2.0 + p;
    m.peak_snr = 10.0 + p;
    result.measurement.pairs.push_back(m);
  }
  result.tdoa_s = 0.004;
  v1::LocateResponse response;
  LocateResultToProto(result, *array, &response);
  ASSERT_EQ(response.pairs_size(), 3);
  EXPECT_EQ(response.pairs(0).sensor(), 0u);
  EXPECT_EQ(response.pairs(1).sensor(), 2u);
  EXPECT_EQ(response.pairs(2).sensor(), 3u);
  EXPECT_EQ(response.pairs(2).delay_s(), result.measurement.pairs[2].delay_s);
  EXPECT_EQ(response.pairs(1).quality(), 3.0);
  EXPECT_EQ(response.pairs(0).peak_snr(), 10.0);
  EXPECT_FALSE(response.fix_found());
  EXPECT_FALSE(response.has_position_m());
  EXPECT_EQ(response.covariance_size(), 0);
  EXPECT_EQ(response.tdoa_s(), 0.004);

  result.fix_found = true;
  result.fix.position_m = engine::Vec3(1.0, 2.0, 3.0);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) result.fix.covariance_m2(r, c) = 10.0 * r + c;
  }
  result.fix.rms_residual_s = 2e-6;
  response.Clear();
  LocateResultToProto(result, *array, &response);
  EXPECT_TRUE(response.fix_found());
  EXPECT_EQ(response.position_m().y(), 2.0);
  ASSERT_EQ(response.covariance_size(), 9);
  EXPECT_EQ(response.covariance(5), 12.0);  // row 1, column 2: row-major
  EXPECT_EQ(response.residual_rms_s(), 2e-6);
}

}  // namespace
}  // namespace localizer::wire
