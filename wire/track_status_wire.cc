#include "wire/track_status_wire.h"

namespace localizer::wire {

v1::TrackStatus TrackStatusToProto(engine::TrackStatus status) {
  switch (status) {
    case engine::TrackStatus::kTentative:
      return v1::TRACK_STATUS_TENTATIVE;
    case engine::TrackStatus::kConfirmed:
      return v1::TRACK_STATUS_CONFIRMED;
    case engine::TrackStatus::kCoasting:
      return v1::TRACK_STATUS_COASTING;
  }
  return v1::TRACK_STATUS_UNSPECIFIED;
}

engine::TrackStatus TrackStatusFromProto(v1::TrackStatus status) {
  switch (status) {
    case v1::TRACK_STATUS_CONFIRMED:
      return engine::TrackStatus::kConfirmed;
    case v1::TRACK_STATUS_COASTING:
      return engine::TrackStatus::kCoasting;
    default:
      return engine::TrackStatus::kTentative;
  }
}

}  // namespace localizer::wire
