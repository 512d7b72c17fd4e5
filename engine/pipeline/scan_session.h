// A detection session: scans of plots in, the track list out (track-while-scan).
//
// Where an audio Session (session.h) measures TDOAs and follows one source, a ScanSession
// takes what a detecting sensor already found -- a search radar's or an active sonar's
// (range, bearing[, elevation]) plots, one Scan per rotation or dwell -- and keeps many
// target tracks with stable identities (engine/tws/tws_tracker.h). Each scan yields the
// tracks after it: tentative, confirmed and coasting, with position, velocity and
// covariance in the world frame.
// Opened with a DetectionSessionConfig (session_config.h). A pure function of its options
// and the scans it was given (no random draws).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "engine/core/detection.h"
#include "engine/pipeline/session_config.h"
#include "engine/tws/track_report.h"
#include "engine/tws/tws_tracker.h"

namespace localizer::engine {

struct ScanResult {
  uint64_t scan_index = 0;               // 0, 1, 2, ... within the session
  double time_s = 0.0;                   // the scan's instant
  std::vector<tws::TrackReport> tracks;  // in order of id, tentative ones included
  tws::ScanSummary summary;
  double process_s = 0.0;  // wall time of the tracker's scan cycle
};

class ScanSession {
 public:
  // INVALID_ARGUMENT unless config.Validate() holds.
  static StatusOr<std::unique_ptr<ScanSession>> Create(const DetectionSessionConfig& config);

  // INVALID_ARGUMENT (the session unchanged) for a scan the tracker refuses: time not finite
  // or not after the previous scan's, a range not finite and > 0, an angle not finite, a
  // 3-D session's plot without elevation. `out` is filled on success.
  Status Process(const Scan& scan, ScanResult* out);

  const DetectionSessionConfig& config() const { return config_; }
  int64_t track_updates() const { return tracker_->total_track_updates(); }

 private:
  ScanSession(DetectionSessionConfig config, std::unique_ptr<tws::TwsTracker> tracker)
      : config_(config), tracker_(std::move(tracker)) {}

  DetectionSessionConfig config_;
  std::unique_ptr<tws::TwsTracker> tracker_;
  uint64_t scans_ = 0;
};

}  // namespace localizer::engine
