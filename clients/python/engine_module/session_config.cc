#include "clients/python/engine_module/session_config.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "clients/python/engine_module/errors.h"
#include "clients/python/engine_module/numpy_convert.h"
#include "engine/filters/filter_kind.h"
#include "engine/filters/imm_filter.h"
#include "engine/filters/kalman_filter.h"
#include "engine/filters/particle_filter.h"
#include "engine/models/motion_model.h"
#include "engine/pipeline/backend.h"
#include "engine/pipeline/session.h"

namespace localizer::python {

namespace {

using engine::AudioSessionConfig;
using Config = AudioSessionConfig;

// One keyword option: how it is written into the config and read back from one.
struct Option {
  std::string name;
  std::function<void(Config&, const py::handle&)> set;
  std::function<py::object(const Config&)> get;
};

template <typename T>
T CastOption(const py::handle& value, const std::string& name, const char* expected) {
  try {
    return value.cast<T>();
  } catch (const py::cast_error&) {
    throw py::type_error("option " + name + ": expected " + expected + ", got " +
                         py::str(value.get_type().attr("__name__")).cast<std::string>());
  }
}

template <typename T, typename Field>
Option Number(const std::string& name, Field field, const char* expected) {
  return {name, [=](Config& c, const py::handle& v) { field(c) = CastOption<T>(v, name, expected); },
          [=](const Config& c) { return py::cast(field(const_cast<Config&>(c))); }};
}
template <typename Field>
Option Double(const std::string& name, Field field) {
  return Number<double>(name, field, "a number");
}
template <typename Field>
Option Int(const std::string& name, Field field) {
  return Number<int>(name, field, "an int");
}

// True or False only (an int is refused, not read as truth).
bool BoolOption(const py::handle& v, const std::string& name) {
  if (!py::isinstance<py::bool_>(v)) {
    throw py::type_error("option " + name + ": expected True or False, got " +
                         py::str(v.get_type().attr("__name__")).cast<std::string>());
  }
  return v.cast<bool>();
}
template <typename Field>
Option Bool(const std::string& name, Field field) {
  return {name, [=](Config& c, const py::handle& v) { field(c) = BoolOption(v, name); },
          [=](const Config& c) { return py::cast(field(const_cast<Config&>(c))); }};
}
// None (the engine decides) or a bool.
template <typename Field>
Option OptionalBool(const std::string& name, Field field) {
  return {name,
          [=](Config& c, const py::handle& v) {
            if (v.is_none()) {
              field(c).reset();
            } else {
              field(c) = BoolOption(v, name);
            }
          },
          [=](const Config& c) {
            const std::optional<bool>& value = field(const_cast<Config&>(c));
            return value ? py::object(py::bool_(*value)) : py::object(py::none());
          }};
}

template <typename Field>
Option Vector(const std::string& name, Field field) {
  return {name, [=](Config& c, const py::handle& v) { field(c) = Vec3From(v, name); },
          [=](const Config& c) {
            const engine::Vec3& v = field(const_cast<Config&>(c));
            return py::object(py::make_tuple(v.x(), v.y(), v.z()));
          }};
}

// A named choice: parsed by the engine's Parse...(name, field), written back by its ...Name.
template <typename Field, typename Parse, typename Name>
Option Choice(const std::string& name, Field field, Parse parse, Name to_name) {
  return {name,
          [=](Config& c, const py::handle& v) {
            field(c) = ValueOrThrow(parse(CastOption<std::string>(v, name, "a name (str)"), name));
          },
          [=](const Config& c) { return py::object(py::str(to_name(field(const_cast<Config&>(c))))); }};
}

const std::vector<Option>& Options() {
  static const std::vector<Option> options = {
      Double("sound_speed_mps", [](Config& c) -> double& { return c.sound_speed_mps; }),
      Int("reference_sensor", [](Config& c) -> int& { return c.reference_sensor; }),
      Int("frame_samples", [](Config& c) -> int& { return c.frame_samples; }),
      Int("hop_samples", [](Config& c) -> int& { return c.hop_samples; }),
      Number<int64_t>(
          "max_block_samples", [](Config& c) -> int64_t& { return c.max_block_samples; }, "an int"),
      Choice(
          "weighting", [](Config& c) -> engine::Weighting& { return c.weighting; },
          [](const std::string& n, const std::string&) { return engine::ParseWeighting(n); }, engine::WeightingName),
      Double("phat_beta", [](Config& c) -> double& { return c.phat_beta; }),
      Double("band_low_hz", [](Config& c) -> double& { return c.band_low_hz; }),
      Double("band_high_hz", [](Config& c) -> double& { return c.band_high_hz; }),
      Double("despike_k", [](Config& c) -> double& { return c.despike_k; }),
      Choice(
          "filter", [](Config& c) -> engine::FilterKind& { return c.tracker.kind; }, engine::ParseFilterKind,
          engine::FilterKindName),
      Choice(
          "motion_model", [](Config& c) -> engine::MotionModelKind& { return c.tracker.kalman.motion_model; },
          engine::ParseMotionModelKind, engine::MotionModelKindName),
      Choice(
          "imm_modes", [](Config& c) -> std::vector<engine::MotionModelKind>& { return c.tracker.imm_modes; },
          engine::ParseImmModes, engine::ImmModesName),
      Choice(
          "imm_variant", [](Config& c) -> engine::KalmanVariant& { return c.tracker.imm_variant; },
          engine::ParseKalmanVariant, engine::KalmanVariantName),
      Choice(
          "robust", [](Config& c) -> engine::RobustUpdate& { return c.tracker.kalman.robust; },
          engine::ParseRobustUpdate, engine::RobustUpdateName),
      Int("particles", [](Config& c) -> int& { return c.tracker.particle.particles; }),
      Choice(
          "likelihood", [](Config& c) -> engine::Likelihood& { return c.tracker.particle.likelihood; },
          [](const std::string& n, const std::string&) { return engine::ParseLikelihood(n); }, engine::LikelihoodName),
      Double("outlier_probability", [](Config& c) -> double& { return c.tracker.particle.outlier_probability; }),
      Double("tdoa_sigma_s", [](Config& c) -> double& { return c.tracker.particle.tdoa_sigma_s; }),
      Double("accel_noise_mps2", [](Config& c) -> double& { return c.tracker.particle.accel_noise_mps2; }),
      Double("manoeuvre_share", [](Config& c) -> double& { return c.tracker.particle.manoeuvre_share; }),
      Double("manoeuvre_scale", [](Config& c) -> double& { return c.tracker.particle.manoeuvre_scale; }),
      Double("accel_level_floor", [](Config& c) -> double& { return c.tracker.particle.accel_level_floor; }),
      Double("accel_level_ceiling", [](Config& c) -> double& { return c.tracker.particle.accel_level_ceiling; }),
      Double("accel_level_switch_hz", [](Config& c) -> double& { return c.tracker.particle.accel_level_switch_hz; }),
      Double("turn_rate_max_radps", [](Config& c) -> double& { return c.tracker.particle.turn_rate_max_radps; }),
      Double("speed_change_max_mps2", [](Config& c) -> double& { return c.tracker.particle.speed_change_max_mps2; }),
      Number<uint64_t>(
          "seed", [](Config& c) -> uint64_t& { return c.seed; }, "a non-negative int"),
      Double("init_speed_sigma_mps", [](Config& c) -> double& { return c.init_speed_sigma_mps; }),
      Vector("init_region_min_m", [](Config& c) -> engine::Vec3& { return c.init_region_min_m; }),
      Vector("init_region_max_m", [](Config& c) -> engine::Vec3& { return c.init_region_max_m; }),
      Int("divergence_window", [](Config& c) -> int& { return c.divergence_window; }),
      Vector("bounds_min_m", [](Config& c) -> engine::Vec3& { return c.bounds_min_m; }),
      Vector("bounds_max_m", [](Config& c) -> engine::Vec3& { return c.bounds_max_m; }),
      Double("search_radius_m", [](Config& c) -> double& { return c.search_radius_m; }),
      Double("presence_false_alarm", [](Config& c) -> double& { return c.presence_false_alarm; }),
      Double("source_timeout_s", [](Config& c) -> double& { return c.source_timeout_s; }),
      Choice(
          "localization", [](Config& c) -> engine::Localization& { return c.localization; }, engine::ParseLocalization,
          engine::LocalizationName),
      Int("max_sources", [](Config& c) -> int& { return c.max_sources; }),
      Vector("source_side", [](Config& c) -> engine::Vec3& { return c.source_side; }),
      Vector("source_plane_point_m", [](Config& c) -> engine::Vec3& { return c.source_plane_point_m; }),
      Vector("source_plane_normal", [](Config& c) -> engine::Vec3& { return c.source_plane_normal; }),
      Choice(
          "backend", [](Config& c) -> engine::BackendChoice& { return c.backend; }, engine::ParseBackendChoice,
          engine::BackendChoiceName),
      Double("direction_present_hold_s", [](Config& c) -> double& { return c.direction_present_hold_s; }),
      Bool("direction_diffuse_weighting", [](Config& c) -> bool& { return c.direction_diffuse_weighting; }),
      OptionalBool("direction_signal_weighting",
                   [](Config& c) -> std::optional<bool>& { return c.direction_signal_weighting; }),
  };
  return options;
}

}  // namespace

engine::AudioSessionConfig SessionConfigFrom(const py::handle& sensors_m, double sample_rate_hz,
                                             const py::dict& options) {
  Config config;
  config.sensors_m = PositionsFrom(sensors_m, "sensors_m");
  config.sample_rate_hz = sample_rate_hz;
  bool frame_given = false, hop_given = false;
  for (const auto& [key, value] : options) {
    const std::string name = py::str(key);
    const auto option =
        std::find_if(Options().begin(), Options().end(), [&](const Option& o) { return o.name == name; });
    if (option == Options().end()) throw py::type_error("Session: unknown option '" + name + "'");
    if (value.is_none()) continue;  // None: the default
    option->set(config, value);
    frame_given |= name == "frame_samples";
    hop_given |= name == "hop_samples";
  }
  // As localizer-cli (session_flags.cc): one motion noise and TDOA noise for every filter.
  engine::TrackerOptions& tracker = config.tracker;
  tracker.kalman.motion.accel_noise_mps2 = tracker.particle.accel_noise_mps2;
  tracker.kalman.tdoa_sigma_s = tracker.particle.tdoa_sigma_s;
  tracker.kalman.min_peak_snr = tracker.particle.min_peak_snr;
  // Sessions that list sources: frames of about 32 ms unless given (the CLI's reason: 4096 is
  // 256 ms at 16 kHz, longer than a talker's syllables).
  auto sources = engine::ReportsSources(config);
  if (sources.ok() && *sources && !frame_given && sample_rate_hz > 0.0 && std::isfinite(sample_rate_hz)) {
    const double frame = std::exp2(std::round(std::log2(std::max(64.0, 0.032 * sample_rate_hz))));
    config.frame_samples = static_cast<int>(std::min(frame, double{1 << 20}));
    if (!hop_given) config.hop_samples = config.frame_samples / 2;
  }
  return config;
}

py::dict DefaultSessionOptions() {
  py::dict defaults;
  const Config config;
  for (const Option& o : Options()) defaults[py::str(o.name)] = o.get(config);
  defaults["frame_samples"] = py::none();  // resolved per session (above)
  defaults["hop_samples"] = py::none();
  return defaults;
}

py::dict SessionConfigToDict(const engine::AudioSessionConfig& config) {
  py::dict out;
  std::vector<double> flat;
  for (const engine::Vec3& m : config.sensors_m) flat.insert(flat.end(), {m.x(), m.y(), m.z()});
  py::array_t<double> sensors({static_cast<py::ssize_t>(config.sensors_m.size()), py::ssize_t{3}});
  std::copy(flat.begin(), flat.end(), sensors.mutable_data());
  out["sensors_m"] = sensors;
  out["sample_rate_hz"] = config.sample_rate_hz;
  for (const Option& o : Options()) out[py::str(o.name)] = o.get(config);
  return out;
}

}  // namespace localizer::python
