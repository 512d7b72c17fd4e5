#include "engine/tws/track_report.h"

namespace localizer::engine::tws {

const char* TrackStatusName(TrackStatus status) {
  switch (status) {
    case TrackStatus::kTentative:
      return "tentative";
    case TrackStatus::kConfirmed:
      return "confirmed";
    case TrackStatus::kCoasting:
      return "coasting";
  }
  return "unknown";
}

}  // namespace localizer::engine::tws
