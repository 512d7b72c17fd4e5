// SessionConfig on the wire <-> engine::SessionConfig (session_config.h): a proto with
// `detections` set is a DetectionSessionConfig, any other an AudioSessionConfig.
//
// Zero (or "", or unset) proto fields take the defaults the proto lists; ConfigToProto
// writes every field explicitly, which is what SessionOpened.effective_config carries and
// what a client sends to reproduce an offline run exactly. The names the proto carries as
// strings (backend, filter.motion_model, filter.imm_modes, filter.imm_variant,
// filter.robust, platform.attitude_filter) are parsed here, once, into the engine's enums.
#pragma once

#include <cstdint>
#include <string>

#include "engine/core/status.h"
#include "engine/pipeline/session_config.h"
#include "localizer/v1/localizer.pb.h"

namespace localizer::wire {

// What the server allows and what it fills in where the client left a field unset.
struct ConfigPolicy {
  std::string default_backend = "auto";  // for backend ""
  int64_t max_block_samples = 1 << 22;   // per channel; also the default
  int max_channels = 64;
  int max_particles = 1 << 20;
  int max_tracks = 10000;          // detection sessions: tracks held at once; also the default
  int max_plots_per_scan = 65536;  // detection sessions: plots in one scan; also the default
  // hop_samples >= frame_samples / this: each sample is analysed in at most this many frames
  // (hop 1 would make one block cost frame_samples times the work of hop = frame).
  int max_frame_overlap = 64;
};

// INVALID_ARGUMENT naming the proto field ("array.sensors_m", "filter.particles",
// "filter.motion_model", ...) for anything the engine would refuse or the policy forbids.
StatusOr<engine::SessionConfig> ConfigFromProto(const v1::SessionConfig& proto, const ConfigPolicy& policy);
// The same for a config that must be an audio session's (INVALID_ARGUMENT "detections: ..."
// for a detection config).
StatusOr<engine::AudioSessionConfig> AudioConfigFromProto(const v1::SessionConfig& proto, const ConfigPolicy& policy);

// Every field set. The backend is written as the config holds it; a server reporting the
// backend it chose sets it on the result. A detection config's backend is "cpu".
v1::SessionConfig ConfigToProto(const engine::SessionConfig& config, const std::string& label);
v1::SessionConfig ConfigToProto(const engine::AudioSessionConfig& config, const std::string& label);
v1::SessionConfig ConfigToProto(const engine::DetectionSessionConfig& config, const std::string& label);

}  // namespace localizer::wire
