// The flags that build an engine::AudioSessionConfig, shared by `track` (local and
// --server), `simulate --server` and `locate`, so that every path builds the same config from
// the same flags: the defaults are engine::AudioSessionConfig's, overridden by the array
// file's "session" object (io/session_file.h), overridden by a flag given on the command
// line; the array comes from the array file (io::TrackConfigFor).
#pragma once

#include <memory>
#include <optional>
#include <set>
#include <string>

#include "clients/io/array_json.h"
#include "clients/io/track_runner.h"
#include "engine/core/flags.h"
#include "engine/core/status.h"
#include "engine/pipeline/session.h"

namespace localizer::cli {

// Numeric fields bind to `config`; names bind to strings (defaults: the engine's, by name)
// that BuildSessionConfig parses, each error naming its field.
struct SessionFlags {
  engine::AudioSessionConfig config;  // numeric fields bound to flags
  std::string weighting = engine::WeightingName(engine::AudioSessionConfig{}.weighting);
  std::string likelihood = engine::LikelihoodName(engine::AudioSessionConfig{}.tracker.particle.likelihood);
  double tdoa_sigma_us = engine::AudioSessionConfig{}.tracker.particle.tdoa_sigma_s * 1e6;
  std::string filter = engine::FilterKindName(engine::AudioSessionConfig{}.tracker.kind);
  std::string motion_model = engine::MotionModelKindName(engine::AudioSessionConfig{}.tracker.kalman.motion_model);
  std::string imm_modes = engine::ImmModesName(engine::AudioSessionConfig{}.tracker.imm_modes);
  std::string imm_variant = engine::KalmanVariantName(engine::AudioSessionConfig{}.tracker.imm_variant);
  std::string robust = engine::RobustUpdateName(engine::AudioSessionConfig{}.tracker.kalman.robust);
  std::string backend = engine::BackendChoiceName(engine::AudioSessionConfig{}.backend);
  io::ArrayOverrides array;        // --sound-speed, --reference, --surface-z, --bottom-z
  std::string bounds_min;          // --bounds-min X,Y,Z ("" = the array file's)
  std::string bounds_max;          // --bounds-max X,Y,Z
  std::string localization;        // --localization ("" = the array file's, else auto)
  std::optional<int> max_sources;  // --max-sources (unset: the array file's, else 4)
  std::string source_side;         // --source-side X,Y,Z ("" = the array file's, else unstated)
  std::string source_plane;        // --source-plane PX,PY,PZ,NX,NY,NZ ("" = the array file's)
  bool delay_rates = false;        // --delay-rates: delay_rate_compensation on
  bool no_closure = false;         // --no-closure: pair_closure off
  bool no_fusion = false;          // --no-fusion: pair_fusion off
  bool no_diffuse = false;         // --no-diffuse-weighting: direction_diffuse_weighting off
  std::string signal_weighting;    // --signal-weighting on|off ("": by the array's shape)
  bool echo_test = false;          // --echo-test: direction_echo_test on
  // Flags the caller counts as given although FlagSet::seen does not (track's deprecated
  // --seed stands for --filter-seed), so that the session file does not override them.
  std::set<std::string> also_given;
};

// --sound-speed, --reference, --weighting, --phat-beta, --band-low, --band-high.
void RegisterGccFlags(FlagSet& flags, SessionFlags* f);
// --frame, --hop, --filter, --motion-model, --imm-modes, --imm-variant, --robust,
// --particles, --likelihood, --outlier-probability, --SEED_FLAG, --tdoa-sigma-us,
// --accel-noise, --backend, --despike-k, --cross-pairs, --no-closure, --no-fusion, --delay-rates,
// --echo-test; source presence
// and bounds: --bounds-min, --bounds-max, --surface-z, --bottom-z, --search-radius,
// --presence-false-alarm, --source-timeout; what is reported: --localization,
// --max-sources, --source-side.
// `seed_flag` names the filter seed's flag ("seed" for track; simulate's
// --seed is the scenario's).
void RegisterTrackerFlags(FlagSet& flags, SessionFlags* f, const std::string& seed_flag);

// "X,Y,Z" with each axis a number or, for an open side, "-inf" (is_min) / "inf" (max);
// INVALID_ARGUMENT naming `flag` and the axis.
StatusOr<engine::Vec3> ParseBoundsFlag(const std::string& flag, const std::string& text, bool is_min);

// Where the session will run: a local engine::Session, or a server.
enum class Runs { kLocally, kOnServer };

// The config from the flags and the array file at `sample_rate_hz`, checked as far as this
// machine can: the names parsed (errors name the field: "filter 'x' is not one of: pf, ...")
// and the config built into a Session (some limits, e.g. band edges against Nyquist, are
// only checked then). For kOnServer the session is built on the CPU, since the server, not
// this machine, must have the GPU. INVALID_ARGUMENT naming the flag or field.
// Each setting of the array file's "session" object applies unless its flag (FlagOfSessionKey)
// was given (`flags.seen`, or f.also_given). When neither --frame nor the file's frame_samples
// is given, sessions that list sources get frames of about 32 ms (the power of two nearest
// 0.032 x the rate, at least 64 samples) and, without --hop / hop_samples, a hop of half a
// frame: the default 4096 is 256 ms at 16 kHz, longer than a talker's syllables and pauses.
// For kLocally, `checked` (when not null) receives the Session built for the check, so that a
// local run can use it instead of building a second one (its buffers, plans and particles:
// ~8 % of a short `track`'s CPU).
StatusOr<engine::AudioSessionConfig> BuildSessionConfig(const SessionFlags& f, const FlagSet& flags,
                                                        const io::ArrayFile& array, double sample_rate_hz, Runs runs,
                                                        std::unique_ptr<engine::Session>* checked = nullptr);

// The flag (without "--") that overrides the session-file key `key` (io::SessionKeys()), e.g.
// "tdoa-sigma-us" for "tdoa_sigma_s"; "" for a key no flag covers (none, today: a test holds
// every key to a flag).
std::string FlagOfSessionKey(const std::string& key);

}  // namespace localizer::cli
