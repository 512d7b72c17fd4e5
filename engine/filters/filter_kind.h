// Which single-source tracker a session runs (engine/pipeline/backend.h builds it):
//   kPf    particle filter (particle_filter.h), on the chosen backend
//   kEkf   extended Kalman filter (kalman_filter.h), over one motion model
//   kUkf   unscented Kalman filter (kalman_filter.h), over one motion model
//   kMmpf  multiple-model particle filter (multi_model_pf.h: cv, cv-manoeuvre, ct-left,
//          ct-right)
//   kImm   interacting multiple model (imm_filter.h) over several Kalman filters
// Names on the wire and in flags: pf, ekf, ukf, mmpf, imm (ParseFilterKind, FilterKindName).
#pragma once

#include <string>

#include "engine/core/status.h"

namespace localizer::engine {

enum class FilterKind { kPf, kEkf, kUkf, kMmpf, kImm };

// INVALID_ARGUMENT "<field> 'x' is not one of: pf, ekf, ukf, mmpf, imm".
StatusOr<FilterKind> ParseFilterKind(const std::string& name, const std::string& field);
const char* FilterKindName(FilterKind kind);

// The kinds that run one Kalman filter over one motion model (their motion_model applies).
inline bool IsSingleKalman(FilterKind kind) { return kind == FilterKind::kEkf || kind == FilterKind::kUkf; }

}  // namespace localizer::engine
