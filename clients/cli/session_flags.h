// The flags that build an engine::SessionConfig, shared by `track` (local and --server),
// `simulate --server` and `locate`, so that every path builds the same config from the same
// flags: the numeric defaults are engine::SessionConfig's, the array comes from the array
// file (io::TrackConfigFor).
#pragma once

#include <string>

#include "clients/io/array_json.h"
#include "clients/io/track_runner.h"
#include "engine/core/flags.h"
#include "engine/core/status.h"
#include "engine/pipeline/session.h"

namespace localizer::cli {

struct SessionFlags {
  engine::SessionConfig config;  // numeric fields bound to flags
  std::string weighting = engine::WeightingName(engine::SessionConfig{}.weighting);
  std::string likelihood = engine::LikelihoodName(engine::SessionConfig{}.filter.likelihood);
  double tdoa_sigma_us = engine::SessionConfig{}.filter.tdoa_sigma_s * 1e6;
  io::ArrayOverrides array;  // --sound-speed, --reference, --surface-z, --bottom-z
  std::string bounds_min;    // --bounds-min X,Y,Z ("" = the array file's)
  std::string bounds_max;    // --bounds-max X,Y,Z
};

// --sound-speed, --reference, --weighting, --phat-beta, --band-low, --band-high.
void RegisterGccFlags(FlagSet& flags, SessionFlags* f);
// --frame, --hop, --particles, --likelihood, --SEED_FLAG, --tdoa-sigma-us, --accel-noise,
// --backend; source presence and bounds: --bounds-min, --bounds-max, --surface-z,
// --bottom-z, --search-radius, --presence-false-alarm, --source-timeout. `seed_flag` names the filter seed's flag ("seed" for track; simulate's --seed
// is the scenario's).
void RegisterTrackerFlags(FlagSet& flags, SessionFlags* f, const std::string& seed_flag);

// "X,Y,Z" with each axis a number or, for an open side, "-inf" (is_min) / "inf" (max);
// INVALID_ARGUMENT naming `flag` and the axis.
StatusOr<engine::Vec3> ParseBoundsFlag(const std::string& flag, const std::string& text, bool is_min);

// Where the session will run: a local engine::Session, or a server.
enum class Runs { kLocally, kOnServer };

// The config from the flags and the array file at `sample_rate_hz`, checked as far as this
// machine can: built into a Session (some limits, e.g. band edges against Nyquist, are only
// checked then). For kOnServer the backend name is only checked for spelling, since the
// server, not this machine, must have the GPU. INVALID_ARGUMENT naming the flag or field.
StatusOr<engine::SessionConfig> BuildSessionConfig(const SessionFlags& f,
                                                   const io::ArrayFile& array,
                                                   double sample_rate_hz, Runs runs);

}  // namespace localizer::cli
