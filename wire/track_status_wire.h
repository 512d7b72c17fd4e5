// TrackStatus (engine/core/track_status.h) on the wire: scans' tracks and direction
// sessions' sources use the same enum.
#pragma once

#include "engine/core/track_status.h"
#include "localizer/v1/localizer.pb.h"

namespace localizer::wire {

v1::TrackStatus TrackStatusToProto(engine::TrackStatus status);
// UNSPECIFIED and unknown values read as tentative.
engine::TrackStatus TrackStatusFromProto(v1::TrackStatus status);

}  // namespace localizer::wire
