// FilterConfig on the wire <-> engine::TrackerOptions (engine/pipeline/backend.h): the
// tracker part of a SessionConfig (config_wire.h). Zero (or "") proto fields keep the
// engine's defaults; TrackerToProto writes every field.
#pragma once

#include "engine/core/status.h"
#include "engine/pipeline/backend.h"
#include "localizer/v1/localizer.pb.h"
#include "wire/config_wire.h"

namespace localizer::wire {

// FilterConfig -> the tracker's options. Its names (motion model, IMM modes and variant,
// robust update) are parsed here, each error naming its proto field (INVALID_ARGUMENT); a
// particle count above policy.max_particles is refused. The one motion noise, TDOA noise and
// pair threshold the proto gives every filter go to both the particle and the Kalman
// filters' options.
Status TrackerFromProto(const v1::FilterConfig& f, const ConfigPolicy& policy, engine::TrackerOptions* t);
// The options as the session's filter reads them (the Kalman filters' noise for ekf, ukf, imm).
void TrackerToProto(const engine::TrackerOptions& t, v1::FilterConfig* f);

}  // namespace localizer::wire
