// The array file's "session" object in the CLI's BuildSessionConfig (clients/cli/session_flags.h):
// a setting in the file builds the same engine::AudioSessionConfig as its flag; a flag given on
// the command line wins over the file (even at the default value); every key has its flag;
// a bad file is INVALID_ARGUMENT naming the file and the key.
#include "clients/cli/session_flags.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "clients/io/array_json.h"
#include "clients/io/session_file.h"
#include "tests/clients/test_util.h"

namespace localizer::cli {
namespace {

using io::testing::TempDir;

constexpr double kRateHz = 11025.0;
constexpr const char* kTetra = R"("sound_speed_mps": 1500, "band_hz": [300, 3000],
                                  "sensors_m": [[0,0,0],[2,0,0],[0,2,0],[0,0,2]])";

std::string ArrayText(const std::string& session, const std::string& more = "") {
  return std::string("{") + kTetra + more + (session.empty() ? "" : R"(, "session": )" + session) + "}";
}

// The config `track` builds from `args` and the array file text, as cmd_track.cc does.
StatusOr<engine::AudioSessionConfig> Build(const std::vector<std::string>& args, const std::string& array_text,
                                           const std::set<std::string>& also_given = {}, Runs runs = Runs::kLocally) {
  FlagSet flags("test", "test");
  SessionFlags f;
  RegisterTrackerFlags(flags, &f, "filter-seed");
  RegisterGccFlags(flags, &f);
  if (Status parsed = flags.Parse(args); !parsed.ok()) return parsed;
  f.also_given = also_given;
  auto array = io::ParseArrayJson(array_text, "session.json", io::ArrayUse::kAuto);
  if (!array.ok()) return array.status();
  return BuildSessionConfig(f, flags, *array, kRateHz, runs);
}

std::string Num(double v) {
  char text[40];
  std::snprintf(text, sizeof text, "%.17g", v);
  return text;
}

// Every field a session key or a flag reaches, and those the builder derives from them (the
// Kalman filters' coupled noise, the band from the hint, the 32 ms frames), exactly.
std::string Fields(const engine::AudioSessionConfig& c) {
  const engine::TrackerOptions& t = c.tracker;
  std::string out =
      "frame=" + std::to_string(c.frame_samples) + " hop=" + std::to_string(c.hop_samples) +
      " weighting=" + engine::WeightingName(c.weighting) + " phat_beta=" + Num(c.phat_beta) +
      " band=" + Num(c.band_low_hz) + "," + Num(c.band_high_hz) + " despike_k=" + Num(c.despike_k) +
      " filter=" + engine::FilterKindName(t.kind) +
      " motion_model=" + engine::MotionModelKindName(t.kalman.motion_model) +
      " imm_modes=" + engine::ImmModesName(t.imm_modes) + " imm_variant=" + engine::KalmanVariantName(t.imm_variant) +
      " robust=" + engine::RobustUpdateName(t.kalman.robust) + " particles=" + std::to_string(t.particle.particles) +
      " likelihood=" + engine::LikelihoodName(t.particle.likelihood) +
      " outlier=" + Num(t.particle.outlier_probability) + " tdoa_sigma_s=" + Num(t.particle.tdoa_sigma_s) + "/" +
      Num(t.kalman.tdoa_sigma_s) + " accel=" + Num(t.particle.accel_noise_mps2) + "/" +
      Num(t.kalman.motion.accel_noise_mps2) + " manoeuvre=" + Num(t.particle.manoeuvre_share) + "," +
      Num(t.particle.manoeuvre_scale) + " levels=" + Num(t.particle.accel_level_floor) + "," +
      Num(t.particle.accel_level_ceiling) + "," + Num(t.particle.accel_level_switch_hz) +
      " turns=" + Num(t.particle.turn_rate_max_radps) + " speed_changes=" + Num(t.particle.speed_change_max_mps2) +
      " seed=" + std::to_string(c.seed) + " search_radius_m=" + Num(c.search_radius_m) +
      " presence_false_alarm=" + Num(c.presence_false_alarm) + " source_timeout_s=" + Num(c.source_timeout_s) +
      " backend=" + engine::BackendChoiceName(c.backend) + " c=" + Num(c.sound_speed_mps) +
      " rate=" + Num(c.sample_rate_hz) + " localization=" + engine::LocalizationName(c.localization) +
      " present_hold_s=" + Num(c.direction_present_hold_s) +
      " diffuse_weighting=" + std::to_string(c.direction_diffuse_weighting) + " signal_weighting=" +
      (c.direction_signal_weighting ? std::to_string(*c.direction_signal_weighting) : std::string("by shape"));
  return out;
}

std::string FieldsOf(const StatusOr<engine::AudioSessionConfig>& config) {
  return config.ok() ? Fields(*config) : "error: " + config.status().message();
}

TEST(SessionFileFlags, TheFileGivesTheConfigItsFlagsGive) {
  const auto from_file = Build({}, ArrayText(R"({"particles": 1024, "frame_samples": 2048, "hop_samples": 1024,
                                                "filter": "ekf"})"));
  const auto from_flags =
      Build({"--particles", "1024", "--frame", "2048", "--hop", "1024", "--filter", "ekf"}, ArrayText(""));
  ASSERT_TRUE(from_file.ok()) << from_file.status().ToString();
  EXPECT_EQ(FieldsOf(from_file), FieldsOf(from_flags));
  EXPECT_EQ(from_file->tracker.kind, engine::FilterKind::kEkf);
  EXPECT_EQ(from_file->tracker.particle.particles, 1024);
  EXPECT_EQ(from_file->frame_samples, 2048);
  EXPECT_EQ(from_file->hop_samples, 1024);
  EXPECT_NE(FieldsOf(from_file), FieldsOf(Build({}, ArrayText(""))));
}

// Every key against its flag, each at a value other than the default: what the file says means
// what the flag says.
TEST(SessionFileFlags, EveryKeyMeansWhatItsFlagMeans) {
  const std::vector<std::pair<std::string, std::string>> settings = {// key's JSON value, flag's text
                                                                     {"2048", "2048"},
                                                                     {"512", "512"},
                                                                     {"\"phat-beta\"", "phat-beta"},
                                                                     {"0.6", "0.6"},
                                                                     {"200", "200"},
                                                                     {"4000", "4000"},
                                                                     {"4", "4"},
                                                                     {"\"ekf\"", "ekf"},
                                                                     {"\"ct\"", "ct"},
                                                                     {"\"ca,cv\"", "ca,cv"},
                                                                     {"\"ukf\"", "ukf"},
                                                                     {"\"huber\"", "huber"},
                                                                     {"1024", "1024"},
                                                                     {"\"mixture\"", "mixture"},
                                                                     {"0.1", "0.1"},
                                                                     {"2.5e-05", "25"},
                                                                     {"0.5", "0.5"},
                                                                     {"0.1", "0.1"},
                                                                     {"5", "5"},
                                                                     {"0.01", "0.01"},
                                                                     {"4", "4"},
                                                                     {"2", "2"},
                                                                     {"0.8", "0.8"},
                                                                     {"1.5", "1.5"},
                                                                     {"42", "42"},
                                                                     {"30", "30"},
                                                                     {"0.01", "0.01"},
                                                                     {"3", "3"},
                                                                     {"\"auto\"", "auto"},
                                                                     {"0.2", "0.2"},
                                                                     {"false", ""},  // a switch
                                                                     {"false", "off"}};
  ASSERT_EQ(settings.size(), io::SessionKeys().size()) << "one value per key, in SessionKeys() order";
  std::string session = "{";
  std::vector<std::string> args;
  for (size_t k = 0; k < settings.size(); ++k) {
    const std::string& key = io::SessionKeys()[k];
    session += (k == 0 ? "\"" : ", \"") + key + "\": " + settings[k].first;
    args.push_back("--" + FlagOfSessionKey(key));
    if (!settings[k].second.empty()) args.push_back(settings[k].second);
  }
  session += "}";
  const auto from_file = Build({}, ArrayText(session));
  const auto from_flags = Build(args, ArrayText(""));
  ASSERT_TRUE(from_file.ok()) << from_file.status().ToString();
  EXPECT_EQ(FieldsOf(from_file), FieldsOf(from_flags));
  // And each differs from the default, so that the comparison tests something.
  const std::string defaults = FieldsOf(Build({}, ArrayText("")));
  for (size_t k = 0; k < settings.size(); ++k) {
    const std::string& key = io::SessionKeys()[k];
    std::vector<std::string> one_args = {"--" + FlagOfSessionKey(key)};
    if (!settings[k].second.empty()) one_args.push_back(settings[k].second);
    if (key == "motion_model") one_args.insert(one_args.end(), {"--filter", "ekf"});  // pf takes only cv
    const auto one = Build(one_args, ArrayText(""));
    ASSERT_TRUE(one.ok()) << key << ": " << one.status().ToString();
    EXPECT_NE(FieldsOf(one), defaults) << key;
  }
}

TEST(SessionFileFlags, EveryKeyHasAFlagThatTheCommandsRegister) {
  FlagSet flags("test", "test");
  SessionFlags f;
  RegisterTrackerFlags(flags, &f, "filter-seed");
  RegisterGccFlags(flags, &f);
  for (const std::string& key : io::SessionKeys()) {
    const std::string flag = FlagOfSessionKey(key);
    ASSERT_FALSE(flag.empty()) << key << " has no flag";
    EXPECT_NE(flags.Usage().find("--" + flag + " "), std::string::npos) << key << ": --" << flag << " not registered";
  }
}

TEST(SessionFileFlags, AFlagGivenWinsOverTheFileEvenAtTheDefault) {
  const std::string array = ArrayText(R"({"particles": 1024, "filter": "ekf", "tdoa_sigma_s": 2.5e-05,
                                          "band_low_hz": 500, "seed": 9})");
  auto config = Build({"--particles", "4096", "--filter", "pf", "--tdoa-sigma-us", "0"}, array);
  ASSERT_TRUE(config.ok()) << config.status().ToString();
  EXPECT_EQ(config->tracker.particle.particles, 4096);
  EXPECT_EQ(config->tracker.kind, engine::FilterKind::kPf);
  EXPECT_EQ(config->tracker.particle.tdoa_sigma_s, 0.0);
  EXPECT_EQ(config->tracker.kalman.tdoa_sigma_s, 0.0);
  EXPECT_EQ(config->band_low_hz, 500.0) << "the file's band, not the array's band_hz hint";
  EXPECT_EQ(config->band_high_hz, 0.0);
  EXPECT_EQ(config->seed, 9u);
  // track's deprecated --seed counts as --filter-seed (cmd_track.cc puts it in also_given).
  auto legacy = Build({}, array, {"filter-seed"});
  ASSERT_TRUE(legacy.ok()) << legacy.status().ToString();
  EXPECT_EQ(legacy->seed, engine::AudioSessionConfig{}.seed);
}

TEST(SessionFileFlags, AFrameInTheFileIsGivenForSessionsThatListSources) {
  const std::string direction = R"(, "localization": "direction")";
  auto derived = Build({}, ArrayText("", direction));
  ASSERT_TRUE(derived.ok()) << derived.status().ToString();
  EXPECT_EQ(derived->frame_samples, 256) << "about 32 ms at 11025 Hz";
  EXPECT_EQ(derived->hop_samples, 128);
  auto from_file = Build({}, ArrayText(R"({"frame_samples": 1024, "hop_samples": 256})", direction));
  ASSERT_TRUE(from_file.ok()) << from_file.status().ToString();
  EXPECT_EQ(from_file->frame_samples, 1024);
  EXPECT_EQ(from_file->hop_samples, 256);
  EXPECT_EQ(FieldsOf(from_file), FieldsOf(Build({"--frame", "1024", "--hop", "256"}, ArrayText("", direction))));
}

// The wire reads 0 as "the default" for these: a 0 asked for cannot reach a server as asked,
// so it is refused for --server (locally it is what it says).
TEST(SessionFileFlags, AZeroTheWireReadsAsTheDefaultIsRefusedForAServer) {
  for (const std::vector<std::string>& args : {std::vector<std::string>{"--accel-noise", "0"},
                                               {"--weighting", "phat-beta", "--phat-beta", "0"},
                                               {"--likelihood", "mixture", "--outlier-probability", "0"}}) {
    EXPECT_TRUE(Build(args, ArrayText("")).ok()) << args[0];
    const auto remote = Build(args, ArrayText(""), {}, Runs::kOnServer);
    ASSERT_FALSE(remote.ok()) << args[args.size() - 2];
    EXPECT_EQ(remote.status().code(), StatusCode::kInvalidArgument);
    EXPECT_NE(remote.status().message().find(args[args.size() - 2] + " 0"), std::string::npos)
        << remote.status().message();
  }
  EXPECT_FALSE(Build({}, ArrayText(R"({"accel_noise_mps2": 0})"), {}, Runs::kOnServer).ok());
  EXPECT_TRUE(Build({"--accel-noise", "1e-6"}, ArrayText(""), {}, Runs::kOnServer).ok());
}

// Engine-only switches the wire does not carry: a server session would run without them.
TEST(SessionFileFlags, AnEngineOnlySwitchIsRefusedForAServerNamingIt) {
  for (const std::string flag : {"--echo-test", "--no-fusion", "--no-closure", "--delay-rates"}) {
    const auto local = Build({flag}, ArrayText(""));
    EXPECT_TRUE(local.ok()) << flag << ": " << local.status().ToString();
    const auto remote = Build({flag}, ArrayText(""), {}, Runs::kOnServer);
    ASSERT_FALSE(remote.ok()) << flag;
    EXPECT_EQ(remote.status().code(), StatusCode::kInvalidArgument);
    EXPECT_NE(remote.status().message().find(flag + " is not carried to a server"), std::string::npos)
        << remote.status().message();
  }
  EXPECT_DOUBLE_EQ(Build({"--present-drop-db", "6"}, ArrayText(""))->direction_present_drop_db, 6.0);
  EXPECT_NE(Build({"--present-drop-db", "6"}, ArrayText(""), {}, Runs::kOnServer)
                .status()
                .message()
                .find("--present-drop-db is not carried"),
            std::string::npos);
  EXPECT_TRUE(Build({"--present-drop-db", "0"}, ArrayText(""), {}, Runs::kOnServer).ok());
  EXPECT_TRUE(Build({"--echo-test"}, ArrayText(""))->direction_echo_test);
  EXPECT_FALSE(Build({}, ArrayText(""))->direction_echo_test);
}

TEST(SessionFileFlags, ABadFileNamesTheFileAndTheKey) {
  TempDir dir;
  const auto write = [&](const std::string& session) {
    std::ofstream(dir.File("array.json")) << ArrayText(session);
    return io::ReadArrayFile(dir.File("array.json"), io::ArrayUse::kAuto);
  };
  auto unknown = write(R"({"particle": 1024})");
  ASSERT_FALSE(unknown.ok());
  EXPECT_EQ(unknown.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(unknown.status().message().find(dir.File("array.json") + ": session: unknown key \"particle\""),
            std::string::npos)
      << unknown.status().message();
  auto bad = write(R"({"filter": "kalman"})");
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(bad.status().message().find(dir.File("array.json") + ": session.filter 'kalman'"), std::string::npos)
      << bad.status().message();
  auto range = write(R"({"particles": 8})");
  ASSERT_FALSE(range.ok());
  EXPECT_EQ(range.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(range.status().message().find(dir.File("array.json") + ": session: particles must be in"),
            std::string::npos)
      << range.status().message();
}

// The closure check is on unless --no-closure; --delay-rates turns the delay-rate reading on.
TEST(SessionFlags, NoClosureAndDelayRatesSetTheirSessionFields) {
  const auto defaults = Build({}, ArrayText(""));
  ASSERT_TRUE(defaults.ok()) << defaults.status().ToString();
  EXPECT_TRUE(defaults->pair_closure);
  EXPECT_FALSE(defaults->delay_rate_compensation);
  const auto flagged = Build({"--no-closure", "--delay-rates"}, ArrayText(""));
  ASSERT_TRUE(flagged.ok()) << flagged.status().ToString();
  EXPECT_FALSE(flagged->pair_closure);
  EXPECT_TRUE(flagged->delay_rate_compensation);
}

}  // namespace
}  // namespace localizer::cli
