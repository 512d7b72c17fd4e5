#include "clients/io/session_file.h"

#include <algorithm>
#include <climits>
#include <set>
#include <utility>

#include "clients/io/json_fields.h"
#include "engine/filters/imm_filter.h"

namespace localizer::io {

namespace {

using engine::AudioSessionConfig;
using nlohmann::json;

// One key: read from JSON into SessionSettings, written back, applied to a config. One table
// of these is the whole format, so reading, writing and applying cannot disagree on a name.
struct Key {
  std::string name;
  std::function<Status(const json& value, const std::string& source, SessionSettings* s)> read;
  std::function<bool(const SessionSettings& s)> is_set;
  std::function<json(const SessionSettings& s)> write;
  std::function<void(const SessionSettings& s, AudioSessionConfig* c)> apply;
};

template <typename T>
using Reader = std::function<StatusOr<T>(const json& value, const std::string& source, const std::string& key)>;

std::string Where(const std::string& source, const std::string& key) { return source + ": session." + key; }

// An integer in [min, max], checked before any cast: 4294967297 must not become 1.
StatusOr<int64_t> ReadInteger(const json& v, const std::string& source, const std::string& key, int64_t min,
                              int64_t max) {
  if (!v.is_number_integer()) return InvalidArgument(Where(source, key) + " is " + v.dump() + ", not an integer");
  const bool in_range = v.is_number_unsigned() ? v.get<uint64_t>() <= static_cast<uint64_t>(max)
                                               : v.get<int64_t>() >= min && v.get<int64_t>() <= max;
  if (!in_range) return InvalidArgument(Where(source, key) + " is " + v.dump() + ", out of range");
  return v.get<int64_t>();
}

StatusOr<int> ReadInt(const json& v, const std::string& source, const std::string& key) {
  auto x = ReadInteger(v, source, key, INT_MIN, INT_MAX);  // the engine's range: Validate()
  if (!x.ok()) return x.status();
  return static_cast<int>(*x);
}

StatusOr<uint64_t> ReadSeed(const json& v, const std::string& source, const std::string& key) {
  if (!v.is_number_unsigned()) {
    return InvalidArgument(Where(source, key) + " is " + v.dump() + ", not an integer >= 0");
  }
  return v.get<uint64_t>();
}

StatusOr<bool> ReadBool(const json& v, const std::string& source, const std::string& key) {
  if (!v.is_boolean()) return InvalidArgument(Where(source, key) + " is " + v.dump() + ", not true or false");
  return v.get<bool>();
}

StatusOr<double> ReadNumber(const json& v, const std::string& source, const std::string& key) {
  return FiniteNumber(v, source, "session." + key);
}

// A name parsed by the engine's Parse…(name, field), its message prefixed with the file.
template <typename T>
Reader<T> ReadName(std::function<StatusOr<T>(const std::string& name, const std::string& field)> parse) {
  return [parse](const json& v, const std::string& source, const std::string& key) -> StatusOr<T> {
    if (!v.is_string()) return InvalidArgument(Where(source, key) + " is " + v.dump() + ", not a name (a string)");
    auto value = parse(v.get<std::string>(), key);
    if (!value.ok()) return InvalidArgument(source + ": session." + value.status().message());
    return value;
  };
}

template <typename T, typename Field>
Key MakeKey(const std::string& name, std::optional<T> SessionSettings::*member, Field field, Reader<T> read,
            std::function<json(const T&)> write) {
  Key k;
  k.name = name;
  k.read = [=](const json& v, const std::string& source, SessionSettings* s) -> Status {
    auto value = read(v, source, name);
    if (!value.ok()) return value.status();
    s->*member = *std::move(value);
    return Status::Ok();
  };
  k.is_set = [=](const SessionSettings& s) { return (s.*member).has_value(); };
  k.write = [=](const SessionSettings& s) { return write(*(s.*member)); };
  k.apply = [=](const SessionSettings& s, AudioSessionConfig* c) {
    if (s.*member) field(*c) = *(s.*member);
  };
  return k;
}

template <typename Field>
Key Int(const std::string& name, std::optional<int> SessionSettings::*member, Field field) {
  return MakeKey<int>(name, member, field, ReadInt, [](const int& v) { return json(v); });
}
template <typename Field>
Key Double(const std::string& name, std::optional<double> SessionSettings::*member, Field field) {
  return MakeKey<double>(name, member, field, ReadNumber, [](const double& v) { return json(v); });
}
template <typename Field>
Key Bool(const std::string& name, std::optional<bool> SessionSettings::*member, Field field) {
  return MakeKey<bool>(name, member, field, ReadBool, [](const bool& v) { return json(v); });
}
template <typename T, typename Field, typename Parse, typename Name>
Key Choice(const std::string& name, std::optional<T> SessionSettings::*member, Field field, Parse parse, Name to_name) {
  return MakeKey<T>(name, member, field, ReadName<T>(parse), [to_name](const T& v) { return json(to_name(v)); });
}

using S = SessionSettings;
using C = AudioSessionConfig;

const std::vector<Key>& Keys() {
  static const std::vector<Key> keys = {
      Int("frame_samples", &S::frame_samples, [](C& c) -> int& { return c.frame_samples; }),
      Int("hop_samples", &S::hop_samples, [](C& c) -> int& { return c.hop_samples; }),
      Choice(
          "weighting", &S::weighting, [](C& c) -> engine::Weighting& { return c.weighting; },
          [](const std::string& n, const std::string&) { return engine::ParseWeighting(n); }, engine::WeightingName),
      Double("phat_beta", &S::phat_beta, [](C& c) -> double& { return c.phat_beta; }),
      Double("band_low_hz", &S::band_low_hz, [](C& c) -> double& { return c.band_low_hz; }),
      Double("band_high_hz", &S::band_high_hz, [](C& c) -> double& { return c.band_high_hz; }),
      Double("despike_k", &S::despike_k, [](C& c) -> double& { return c.despike_k; }),
      Choice(
          "filter", &S::filter, [](C& c) -> engine::FilterKind& { return c.tracker.kind; }, engine::ParseFilterKind,
          engine::FilterKindName),
      Choice(
          "motion_model", &S::motion_model,
          [](C& c) -> engine::MotionModelKind& { return c.tracker.kalman.motion_model; }, engine::ParseMotionModelKind,
          engine::MotionModelKindName),
      Choice(
          "imm_modes", &S::imm_modes, [](C& c) -> std::vector<engine::MotionModelKind>& { return c.tracker.imm_modes; },
          engine::ParseImmModes, engine::ImmModesName),
      Choice(
          "imm_variant", &S::imm_variant, [](C& c) -> engine::KalmanVariant& { return c.tracker.imm_variant; },
          engine::ParseKalmanVariant, engine::KalmanVariantName),
      Choice(
          "robust", &S::robust, [](C& c) -> engine::RobustUpdate& { return c.tracker.kalman.robust; },
          engine::ParseRobustUpdate, engine::RobustUpdateName),
      Int("particles", &S::particles, [](C& c) -> int& { return c.tracker.particle.particles; }),
      Choice(
          "likelihood", &S::likelihood, [](C& c) -> engine::Likelihood& { return c.tracker.particle.likelihood; },
          [](const std::string& n, const std::string&) { return engine::ParseLikelihood(n); }, engine::LikelihoodName),
      Double("outlier_probability", &S::outlier_probability,
             [](C& c) -> double& { return c.tracker.particle.outlier_probability; }),
      Double("tdoa_sigma_s", &S::tdoa_sigma_s, [](C& c) -> double& { return c.tracker.particle.tdoa_sigma_s; }),
      Double("accel_noise_mps2", &S::accel_noise_mps2,
             [](C& c) -> double& { return c.tracker.particle.accel_noise_mps2; }),
      Double("manoeuvre_share", &S::manoeuvre_share,
             [](C& c) -> double& { return c.tracker.particle.manoeuvre_share; }),
      Double("manoeuvre_scale", &S::manoeuvre_scale,
             [](C& c) -> double& { return c.tracker.particle.manoeuvre_scale; }),
      Double("accel_level_floor", &S::accel_level_floor,
             [](C& c) -> double& { return c.tracker.particle.accel_level_floor; }),
      Double("accel_level_ceiling", &S::accel_level_ceiling,
             [](C& c) -> double& { return c.tracker.particle.accel_level_ceiling; }),
      Double("accel_level_switch_hz", &S::accel_level_switch_hz,
             [](C& c) -> double& { return c.tracker.particle.accel_level_switch_hz; }),
      Double("turn_rate_max_radps", &S::turn_rate_max_radps,
             [](C& c) -> double& { return c.tracker.particle.turn_rate_max_radps; }),
      Double("speed_change_max_mps2", &S::speed_change_max_mps2,
             [](C& c) -> double& { return c.tracker.particle.speed_change_max_mps2; }),
      MakeKey<uint64_t>(
          "seed", &S::seed, [](C& c) -> uint64_t& { return c.seed; }, ReadSeed,
          [](const uint64_t& v) { return json(v); }),
      Double("search_radius_m", &S::search_radius_m, [](C& c) -> double& { return c.search_radius_m; }),
      Double("presence_false_alarm", &S::presence_false_alarm, [](C& c) -> double& { return c.presence_false_alarm; }),
      Double("source_timeout_s", &S::source_timeout_s, [](C& c) -> double& { return c.source_timeout_s; }),
      Choice(
          "backend", &S::backend, [](C& c) -> engine::BackendChoice& { return c.backend; }, engine::ParseBackendChoice,
          engine::BackendChoiceName),
      Double("direction_present_hold_s", &S::direction_present_hold_s,
             [](C& c) -> double& { return c.direction_present_hold_s; }),
      Bool("direction_diffuse_weighting", &S::direction_diffuse_weighting,
           [](C& c) -> bool& { return c.direction_diffuse_weighting; }),
      Bool("direction_signal_weighting", &S::direction_signal_weighting,
           [](C& c) -> std::optional<bool>& { return c.direction_signal_weighting; }),
  };
  return keys;
}

// Keys that mean something elsewhere, refused with where they belong rather than as unknown.
const std::set<std::string> kTopLevelKeys = {
    "sound_speed_mps", "sample_rate_hz",       "sensors_m",           "reference_sensor", "band_hz",     "bounds_min_m",
    "bounds_max_m",    "surface_z_m",          "bottom_z_m",          "localization",     "source_side", "max_sources",
    "source_plane",    "source_plane_point_m", "source_plane_normal", "geodetic_origin"};
const std::set<std::string> kEngineOnlyKeys = {"max_block_samples", "init_speed_sigma_mps", "init_region_min_m",
                                               "init_region_max_m", "divergence_window"};

Status RefuseKey(const std::string& key, const std::string& source) {
  if (kTopLevelKeys.contains(key)) {
    return InvalidArgument(source + ": session." + key +
                           ": give it at the top level of the array file, beside sensors_m, not in \"session\"");
  }
  if (kEngineOnlyKeys.contains(key)) {
    return InvalidArgument(source + ": session." + key +
                           ": not a session-file key: localizer-cli has no flag for it (pass it to "
                           "localizer.engine.Session directly)");
  }
  std::string known;
  for (const std::string& name : SessionKeys()) known += (known.empty() ? "" : ", ") + name;
  return InvalidArgument(source + ": session: unknown key \"" + key + "\" (known: " + known + ")");
}

// The ranges, by the engine: the defaults with the file's settings applied must validate.
// The array and the rate are stand-ins (valid, the largest rate so that no band is refused
// against a Nyquist frequency the recording may not have).
Status CheckRanges(const SessionSettings& settings, const std::string& source) {
  AudioSessionConfig config;
  config.sensors_m = {engine::Vec3::Zero(), engine::Vec3::UnitX()};
  config.sample_rate_hz = 10e6;
  ApplySessionSettings(settings, nullptr, &config);
  if (Status status = config.Validate(); !status.ok())
    return InvalidArgument(source + ": session: " + status.message());
  if (Status status = config.GccOptionsFor().Validate(); !status.ok()) {
    // "GccOptions.phat_beta is 2; ...": the GCC's field names are the keys.
    const std::string prefix = "GccOptions.";
    std::string message = status.message();
    if (message.starts_with(prefix)) message.erase(0, prefix.size());
    return InvalidArgument(source + ": session: " + message);
  }
  return Status::Ok();
}

}  // namespace

bool SessionSettings::empty() const {
  for (const Key& k : Keys()) {
    if (k.is_set(*this)) return false;
  }
  return true;
}

const std::vector<std::string>& SessionKeys() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> out;
    for (const Key& k : Keys()) out.push_back(k.name);
    return out;
  }();
  return names;
}

Status ParseSessionSettings(const json& value, const std::string& source, SessionSettings* out) {
  if (!value.is_object()) {
    return InvalidArgument(source + ": session is " + value.dump() +
                           ", not an object of settings ({\"particles\": ...})");
  }
  SessionSettings settings;
  for (const auto& item : value.items()) {
    const auto key = std::find_if(Keys().begin(), Keys().end(), [&](const Key& k) { return k.name == item.key(); });
    if (key == Keys().end()) return RefuseKey(item.key(), source);
    LOCALIZER_RETURN_IF_ERROR(key->read(item.value(), source, &settings));
  }
  LOCALIZER_RETURN_IF_ERROR(CheckRanges(settings, source));
  *out = std::move(settings);
  return Status::Ok();
}

json SessionSettingsToJson(const SessionSettings& settings) {
  json out = json::object();
  for (const Key& k : Keys()) {
    if (k.is_set(settings)) out[k.name] = k.write(settings);
  }
  return out;
}

void ApplySessionSettings(const SessionSettings& settings, const std::function<bool(const std::string& key)>& keep,
                          AudioSessionConfig* config) {
  for (const Key& k : Keys()) {
    if (!keep || !keep(k.name)) k.apply(settings, config);
  }
}

}  // namespace localizer::io
