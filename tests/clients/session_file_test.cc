// The array file's "session" object (clients/io/session_file.h): every key read, written back
// and read again the same; an array file without it unchanged; unknown, misplaced and
// engine-only keys, wrong types, unknown names and out-of-range values refused as
// INVALID_ARGUMENT naming the file and the key.
#include "clients/io/session_file.h"

#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "clients/io/array_json.h"
#include "tests/clients/test_util.h"

namespace localizer::io {
namespace {

using testing::TempDir;

constexpr const char* kTetraSensors = R"("sound_speed_mps": 1500, "sensors_m": [[0,0,0],[2,0,0],[0,2,0],[0,0,2]])";

// An array file with `session` as its "session" value.
std::string WithSession(const std::string& session) {
  return std::string("{") + kTetraSensors + R"(, "session": )" + session + "}";
}

// "" when the file parses, else the message.
std::string ErrorOf(const std::string& session) {
  auto array = ParseArrayJson(WithSession(session), "dir/session.json");
  if (array.ok()) return "";
  EXPECT_EQ(array.status().code(), StatusCode::kInvalidArgument);
  return array.status().message();
}

// Every key, none at its default, the settings consistent with each other.
constexpr const char* kEveryKey = R"({
  "frame_samples": 2048, "hop_samples": 512, "weighting": "phat-beta", "phat_beta": 0.6,
  "band_low_hz": 200, "band_high_hz": 4000, "despike_k": 4, "filter": "ekf", "motion_model": "ct",
  "imm_modes": "ca,cv", "imm_variant": "ukf", "robust": "huber", "particles": 1024, "likelihood": "mixture",
  "outlier_probability": 0.1, "tdoa_sigma_s": 2.5e-05, "accel_noise_mps2": 0.5, "manoeuvre_share": 0.1,
  "manoeuvre_scale": 5, "accel_level_floor": 0.01, "accel_level_ceiling": 3, "accel_level_switch_hz": 2,
  "turn_rate_max_radps": 0.8, "speed_change_max_mps2": 1.5, "seed": 18446744073709551615, "search_radius_m": 30, "presence_false_alarm": 0.01, "source_timeout_s": 3,
  "backend": "auto", "direction_present_hold_s": 0.1, "direction_diffuse_weighting": false,
  "direction_signal_weighting": false
})";

TEST(SessionFile, ReadsEveryKey) {
  auto array = ParseArrayJson(WithSession(kEveryKey), "session.json");
  ASSERT_TRUE(array.ok()) << array.status().ToString();
  const SessionSettings& s = array->session;
  EXPECT_EQ(s.frame_samples, 2048);
  EXPECT_EQ(s.hop_samples, 512);
  EXPECT_EQ(s.weighting, engine::Weighting::kPhatBeta);
  EXPECT_EQ(s.phat_beta, 0.6);
  EXPECT_EQ(s.band_low_hz, 200.0);
  EXPECT_EQ(s.band_high_hz, 4000.0);
  EXPECT_EQ(s.despike_k, 4.0);
  EXPECT_EQ(s.filter, engine::FilterKind::kEkf);
  EXPECT_EQ(s.motion_model, engine::MotionModelKind::kCt);
  ASSERT_TRUE(s.imm_modes.has_value());
  EXPECT_EQ(*s.imm_modes,
            (std::vector<engine::MotionModelKind>{engine::MotionModelKind::kCa, engine::MotionModelKind::kCv}));
  EXPECT_EQ(s.imm_variant, engine::KalmanVariant::kUnscented);
  EXPECT_EQ(s.robust, engine::RobustUpdate::kHuber);
  EXPECT_EQ(s.particles, 1024);
  EXPECT_EQ(s.likelihood, engine::Likelihood::kMixture);
  EXPECT_EQ(s.outlier_probability, 0.1);
  EXPECT_EQ(s.tdoa_sigma_s, 2.5e-05);
  EXPECT_EQ(s.accel_noise_mps2, 0.5);
  EXPECT_EQ(s.manoeuvre_share, 0.1);
  EXPECT_EQ(s.manoeuvre_scale, 5.0);
  EXPECT_EQ(s.accel_level_floor, 0.01);
  EXPECT_EQ(s.accel_level_ceiling, 3.0);
  EXPECT_EQ(s.accel_level_switch_hz, 2.0);
  EXPECT_EQ(s.turn_rate_max_radps, 0.8);
  EXPECT_EQ(s.speed_change_max_mps2, 1.5);
  EXPECT_EQ(s.seed, 18446744073709551615ull);
  EXPECT_EQ(s.search_radius_m, 30.0);
  EXPECT_EQ(s.presence_false_alarm, 0.01);
  EXPECT_EQ(s.source_timeout_s, 3.0);
  EXPECT_EQ(s.backend, engine::BackendChoice::kAuto);
  EXPECT_EQ(s.direction_present_hold_s, 0.1);
  EXPECT_EQ(s.direction_diffuse_weighting, false);
  EXPECT_EQ(s.direction_signal_weighting, false);
  // The test names every key: a key added to the format must be added here.
  EXPECT_EQ(SessionSettingsToJson(s).size(), SessionKeys().size());
}

TEST(SessionFile, WriteThenReadRoundTrips) {
  TempDir dir;
  auto array = ParseArrayJson(WithSession(kEveryKey), "session.json");
  ASSERT_TRUE(array.ok()) << array.status().ToString();
  ASSERT_TRUE(WriteArrayJson(dir.File("array.json"), *array).ok());
  auto read = ReadArrayJson(dir.File("array.json"));
  ASSERT_TRUE(read.ok()) << read.status().ToString();
  EXPECT_EQ(SessionSettingsToJson(read->session), SessionSettingsToJson(array->session));
  EXPECT_EQ(SessionSettingsToJson(read->session), nlohmann::json::parse(kEveryKey));
}

TEST(SessionFile, AnArrayFileWithoutItIsUnchanged) {
  TempDir dir;
  auto array = ParseArrayJson(std::string("{") + kTetraSensors + "}", "array.json");
  ASSERT_TRUE(array.ok()) << array.status().ToString();
  EXPECT_TRUE(array->session.empty());
  ASSERT_TRUE(WriteArrayJson(dir.File("array.json"), *array).ok());
  std::ifstream in(dir.File("array.json"));
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text.find("session"), std::string::npos) << "no empty session object is written";
  auto empty = ParseArrayJson(WithSession("{}"), "array.json");
  ASSERT_TRUE(empty.ok()) << empty.status().ToString();
  EXPECT_TRUE(empty->session.empty());
}

TEST(SessionFile, AnUnknownKeyIsNamedWithTheFile) {
  const std::string error = ErrorOf(R"({"partcles": 1024})");
  EXPECT_NE(error.find("dir/session.json"), std::string::npos) << error;
  EXPECT_NE(error.find("unknown key \"partcles\""), std::string::npos) << error;
  EXPECT_NE(error.find("particles"), std::string::npos) << "the known keys are listed: " << error;
}

TEST(SessionFile, AKeyOfTheArraysTopLevelSaysWhereItBelongs) {
  for (const char* key : {"sound_speed_mps", "reference_sensor", "bounds_min_m", "localization", "max_sources",
                          "source_side", "source_plane_normal"}) {
    const std::string error = ErrorOf(std::string(R"({")") + key + R"(": 1})");
    EXPECT_NE(error.find("dir/session.json: session." + std::string(key)), std::string::npos) << error;
    EXPECT_NE(error.find("top level"), std::string::npos) << error;
  }
}

TEST(SessionFile, AnEngineOnlyOptionIsRefusedSayingWhy) {
  for (const char* key : {"divergence_window", "init_speed_sigma_mps", "init_region_min_m", "max_block_samples"}) {
    const std::string error = ErrorOf(std::string(R"({")") + key + R"(": 1})");
    EXPECT_NE(error.find("dir/session.json: session." + std::string(key)), std::string::npos) << error;
    EXPECT_NE(error.find("no flag"), std::string::npos) << error;
  }
}

TEST(SessionFile, WrongTypesNameTheKey) {
  const std::pair<const char*, const char*> cases[] = {
      {R"({"particles": "many"})", "session.particles is \"many\", not an integer"},
      {R"({"particles": 1024.5})", "session.particles is 1024.5, not an integer"},
      {R"({"frame_samples": true})", "session.frame_samples is true, not an integer"},
      {R"({"frame_samples": 4294967297})", "session.frame_samples is 4294967297, out of range"},
      {R"({"seed": -1})", "session.seed is -1, not an integer >= 0"},
      {R"({"accel_noise_mps2": "1"})", "session.accel_noise_mps2 is \"1\", not a number"},
      {R"({"filter": 2})", "session.filter is 2, not a name"},
      {R"({"direction_diffuse_weighting": 1})", "session.direction_diffuse_weighting is 1, not true or false"},
      {R"({"direction_signal_weighting": "on"})", "session.direction_signal_weighting is \"on\", not true or false"},
      {R"([1, 2])", "session is [1,2], not an object"},
  };
  for (const auto& [session, expected] : cases) {
    const std::string error = ErrorOf(session);
    EXPECT_NE(error.find(std::string("dir/session.json: ") + expected), std::string::npos)
        << session << " -> " << error;
  }
}

TEST(SessionFile, UnknownNamesAreTheEnginesRefusals) {
  const std::pair<const char*, const char*> cases[] = {
      {R"({"filter": "kalman"})", "session.filter 'kalman' is not one of: pf, ekf, ukf, mmpf, imm"},
      {R"({"motion_model": "cw"})", "session.motion_model 'cw' is not one of: cv, ca, ct, singer"},
      {R"({"imm_modes": "cv,cv"})", "session.imm_modes 'cv,cv' names 'cv' twice"},
      {R"({"weighting": "gcc"})", "session.weighting \"gcc\" is not one of"},
      {R"({"likelihood": "exact"})", "session.likelihood 'exact' is not one of: peak, gcc, mixture"},
      {R"({"backend": "tpu"})", "session.backend 'tpu' is not one of: auto, cpu, gpu"},
  };
  for (const auto& [session, expected] : cases) {
    const std::string error = ErrorOf(session);
    EXPECT_NE(error.find(std::string("dir/session.json: ") + expected), std::string::npos)
        << session << " -> " << error;
  }
}

TEST(SessionFile, RangesAreTheEnginesAgainstTheDefaultsOfWhatIsLeftOut) {
  EXPECT_NE(ErrorOf(R"({"particles": 0})").find("dir/session.json: session: particles must be in [16, 4194304], got 0"),
            std::string::npos);
  EXPECT_NE(ErrorOf(R"({"presence_false_alarm": 0.5})").find("dir/session.json: session: presence_false_alarm"),
            std::string::npos);
  EXPECT_NE(ErrorOf(R"({"phat_beta": 2})").find("dir/session.json: session: phat_beta"), std::string::npos);
  EXPECT_NE(ErrorOf(R"({"band_low_hz": 3000, "band_high_hz": 300})").find("dir/session.json: session: band_high_hz"),
            std::string::npos);
  EXPECT_NE(ErrorOf(R"({"direction_present_hold_s": 2})").find("session: direction_present_hold_s must be in [0, 1]"),
            std::string::npos);
  EXPECT_NE(ErrorOf(R"({"frame_samples": 32})").find("dir/session.json: session: frame_samples"), std::string::npos);
  // Checked together, against the default of what the file leaves out.
  EXPECT_NE(ErrorOf(R"({"hop_samples": 8192})").find("hop_samples must be in [1, frame_samples=4096]"),
            std::string::npos);
  EXPECT_EQ(ErrorOf(R"({"hop_samples": 8192, "frame_samples": 16384})"), "");
  EXPECT_NE(ErrorOf(R"({"motion_model": "ct"})").find("needs filter ekf or ukf"), std::string::npos);
  EXPECT_EQ(ErrorOf(R"({"motion_model": "ct", "filter": "ukf"})"), "");
  // The band against the recording's Nyquist frequency is checked when the session is built.
  EXPECT_EQ(ErrorOf(R"({"band_high_hz": 20000})"), "");
}

TEST(SessionFile, ApplyLeavesTheKeysItIsToldToKeep) {
  auto array = ParseArrayJson(WithSession(R"({"particles": 1024, "filter": "ekf"})"), "session.json");
  ASSERT_TRUE(array.ok()) << array.status().ToString();
  engine::AudioSessionConfig config;
  ApplySessionSettings(
      array->session, [](const std::string& key) { return key == "particles"; }, &config);
  EXPECT_EQ(config.tracker.kind, engine::FilterKind::kEkf);
  EXPECT_EQ(config.tracker.particle.particles, engine::AudioSessionConfig{}.tracker.particle.particles);
  ApplySessionSettings(array->session, nullptr, &config);
  EXPECT_EQ(config.tracker.particle.particles, 1024);
}

// The direction keys land where the flags put them; direction_signal_weighting unset leaves
// the engine's choice by the array's shape (the optional stays empty).
TEST(SessionFile, DirectionKeysSetTheDirectionOptions) {
  auto array = ParseArrayJson(WithSession(R"({"direction_present_hold_s": 0, "direction_diffuse_weighting": false,
                                              "direction_signal_weighting": true})"),
                              "session.json");
  ASSERT_TRUE(array.ok()) << array.status().ToString();
  engine::AudioSessionConfig config;
  ApplySessionSettings(array->session, nullptr, &config);
  EXPECT_EQ(config.direction_present_hold_s, 0.0);
  EXPECT_FALSE(config.direction_diffuse_weighting);
  EXPECT_EQ(config.direction_signal_weighting, std::optional<bool>(true));

  auto unset = ParseArrayJson(WithSession(R"({"particles": 1024})"), "session.json");
  ASSERT_TRUE(unset.ok()) << unset.status().ToString();
  engine::AudioSessionConfig defaults;
  ApplySessionSettings(unset->session, nullptr, &defaults);
  EXPECT_FALSE(defaults.direction_signal_weighting.has_value());
  EXPECT_EQ(defaults.direction_present_hold_s, engine::AudioSessionConfig{}.direction_present_hold_s);
  EXPECT_TRUE(defaults.direction_diffuse_weighting);
}

}  // namespace
}  // namespace localizer::io
