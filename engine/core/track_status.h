// A followed track's status, shared by the track-while-scan tracker (engine/tws) and
// direction sessions' sources (Estimate::sources): kTentative until confirmed (M of N),
// kConfirmed, kCoasting when confirmed but not updated on the latest scan or frame (its
// estimate is then a prediction).
#pragma once

namespace localizer::engine {

enum class TrackStatus { kTentative, kConfirmed, kCoasting };

// "tentative" | "confirmed" | "coasting"
constexpr const char* TrackStatusName(TrackStatus status) {
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

}  // namespace localizer::engine
