// The "session" object of an array file (array_json.h): the tracking settings of a session,
// so that one file describes the whole session (array + settings) to every reader alike:
// localizer-cli (track, locally and with --server; locate; doa where the settings apply), the
// Python engine (localizer.engine.Session) and the Python gRPC client (pb.SessionConfig),
// through localizer.session_file (clients/python/localizer/session_file.py).
//
// The keys are localizer.engine.Session's keyword option names
// (clients/python/engine_module/session_config.cc), SI units in the names, so that there is
// one vocabulary; each stands for one localizer-cli flag, which wins when given (the file's
// values are the defaults; clients/cli/session_flags.h). Unset keys take the engine's default
// (engine::AudioSessionConfig), as an absent flag does.
//
//   "session": {
//     "frame_samples": 2048,          int, samples per channel per frame      --frame
//     "hop_samples": 1024,            int, samples between frame starts       --hop
//     "weighting": "phat",            phat | phat-beta | scot | cc |          --weighting
//                                     phat-coherence | phat-share
//     "phat_beta": 0.8,               [0, 1]                                  --phat-beta
//     "band_low_hz": 300,             the GCC band, Hz (given, the array's    --band-low
//     "band_high_hz": 3000,           band_hz hint is not used)               --band-high
//     "despike_k": 5,                 0 (off) or [1, 1e6]                     --despike-k
//     "filter": "pf",                 pf | ekf | ukf | mmpf | imm             --filter
//     "motion_model": "cv",           cv | ca | ct | singer (ekf, ukf)        --motion-model
//     "imm_modes": "cv,ct",           imm: its modes' motion models           --imm-modes
//     "imm_variant": "ekf",           imm: ekf | ukf                          --imm-variant
//     "robust": "none",               none | huber | student-t                --robust
//     "particles": 4096,              int, [16, 4194304]                      --particles
//     "likelihood": "peak",           peak | gcc | mixture                    --likelihood
//     "outlier_probability": 0.05,    mixture: [0, 1)                         --outlier-probability
//     "tdoa_sigma_s": 2e-05,          s, >= 0 (0: adaptive)                   --tdoa-sigma-us (us)
//     "accel_noise_mps2": 1.0,        m/s^2, >= 0                             --accel-noise
//     "manoeuvre_share": 0.0,         [0, 1)                                  --manoeuvre-share
//     "manoeuvre_scale": 10.0,        >= 1                                    --manoeuvre-scale
//     "accel_level_floor": 0.003,     1e-6 <= floor <= ceiling <= 100         --accel-level-floor
//     "accel_level_ceiling": 3.0,     (both 1: one std)                       --accel-level-ceiling
//     "accel_level_switch_hz": 1.0,   Hz, [0, 1000]                           --accel-level-switch
//     "turn_rate_max_radps": 1.0,     rad/s, [0, 5] (0: off)                  --turn-rate-max
//     "speed_change_max_mps2": 1.0,   m/s^2, [0, 20] (0: off)                 --speed-change-max
//     "seed": 1,                      the filter's seed, integer >= 0         --filter-seed
//     "search_radius_m": 0.0,         m, [0, 1e7] (0: 10 apertures)           --search-radius
//     "presence_false_alarm": 0.001,  per frame, (0, 0.1]                     --presence-false-alarm
//     "source_timeout_s": 2.0,        s, (0, 1e6]                             --source-timeout
//     "backend": "cpu",               cpu | gpu | auto                        --backend
//     "direction_present_hold_s": 0,  s, [0, 1]: direction sessions' hold     --present-hold
//     "direction_diffuse_weighting": true,   bool                             --no-diffuse-weighting
//     "direction_signal_weighting": true     bool (unset: by the array's      --signal-weighting
//                                     shape)
//   }
//
// Not here, and why:
//   - what the array file's top level already says (sound_speed_mps, reference_sensor,
//     bounds_*, surface_z_m / bottom_z_m, localization, max_sources, source_side,
//     source_plane): one place per setting; in "session" such a key is refused, saying so;
//   - localizer.engine options with no localizer-cli flag (max_block_samples,
//     init_speed_sigma_mps, init_region_min_m / init_region_max_m, divergence_window): a
//     file the CLI reads must not carry what the CLI would ignore; refused, saying so;
//   - direction options the wire does not carry (--echo-test, --present-drop-db): the Python
//     gRPC client could not send them;
//   - what a run reads rather than the session (the input, --out, --format, --block,
//     --print-every, --server and the stream flags).
//
// Checks, each error INVALID_ARGUMENT naming the file and the key: an unknown key; a value of
// the wrong JSON type (an integer key takes only integers, a number key any finite number, a
// name key a string, a bool key true or false); a name the engine does not know (parsed by
// the engine's own Parse…); and the ranges, by the engine's own validation (engine::AudioSessionConfig::Validate and
// GccOptions::Validate) of the defaults with the file's settings applied: "<file>: session:
// particles must be in [16, 4194304], got 0". So the settings must agree with each other
// and with the defaults of what they leave out (hop_samples <= frame_samples, which is 4096
// when unset; a motion_model other than cv needs filter ekf or ukf). What depends on the
// recording (the band against its Nyquist frequency) or the machine (backend gpu) is checked
// when the session is built.
#pragma once

#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "engine/core/status.h"
#include "engine/pipeline/session_config.h"

namespace localizer::io {

// The file's settings; an unset one is not stated (the flag or the engine default applies).
struct SessionSettings {
  // Framing and the GCC front end
  std::optional<int> frame_samples;
  std::optional<int> hop_samples;
  std::optional<engine::Weighting> weighting;
  std::optional<double> phat_beta;
  std::optional<double> band_low_hz;
  std::optional<double> band_high_hz;
  std::optional<double> despike_k;
  // Tracker (engine::TrackerOptions); the particle filter's noise options drive every filter
  // kind, as the flags do (clients/cli/session_flags.cc)
  std::optional<engine::FilterKind> filter;
  std::optional<engine::MotionModelKind> motion_model;
  std::optional<std::vector<engine::MotionModelKind>> imm_modes;
  std::optional<engine::KalmanVariant> imm_variant;
  std::optional<engine::RobustUpdate> robust;
  std::optional<int> particles;
  std::optional<engine::Likelihood> likelihood;
  std::optional<double> outlier_probability;
  std::optional<double> tdoa_sigma_s;
  std::optional<double> accel_noise_mps2;
  std::optional<double> manoeuvre_share;
  std::optional<double> manoeuvre_scale;
  std::optional<double> accel_level_floor;
  std::optional<double> accel_level_ceiling;
  std::optional<double> accel_level_switch_hz;
  std::optional<double> turn_rate_max_radps;
  std::optional<double> speed_change_max_mps2;
  std::optional<uint64_t> seed;
  // Acquisition, presence, backend
  std::optional<double> search_radius_m;
  std::optional<double> presence_false_alarm;
  std::optional<double> source_timeout_s;
  std::optional<engine::BackendChoice> backend;
  // Direction sessions (engine/doa)
  std::optional<double> direction_present_hold_s;
  std::optional<bool> direction_diffuse_weighting;
  std::optional<bool> direction_signal_weighting;

  bool empty() const;  // no key set
};

// Every key the "session" object takes, in the order above.
const std::vector<std::string>& SessionKeys();

// Reads `value` (the "session" object of the file named `source`) into `out`, all the
// checks above; INVALID_ARGUMENT naming `source` and the key.
Status ParseSessionSettings(const nlohmann::json& value, const std::string& source, SessionSettings* out);

// The set keys as a "session" object (what ParseSessionSettings reads back the same).
nlohmann::json SessionSettingsToJson(const SessionSettings& settings);

// Writes each set key into the field of `config` its option name stands for (the particle
// filter's options for the noise settings: the caller couples them to the Kalman filters, as
// BuildSessionConfig does), except the keys `keep(key)` says to leave as they are (a flag was
// given). No check: ParseSessionSettings did those, Session::Create does the rest.
void ApplySessionSettings(const SessionSettings& settings, const std::function<bool(const std::string& key)>& keep,
                          engine::AudioSessionConfig* config);

}  // namespace localizer::io
