// The frame step of a direction session (AudioSessionConfig::localization resolved to
// direction): each frame's SRP-PHAT peaks (engine/doa/srp_phat.h) go to a direction
// tracker (engine/doa/direction_tracker.h), and the estimate lists the sources it follows.
//
// Per frame: up to config.max_sources peaks, each above the threshold set by
// config.presence_false_alarm per search; the tracker associates them with its tracks
// (identities kept through pauses of up to max_coast_s), confirms new ones after M of N
// frames and deletes silent ones. Estimate::sources gets the confirmed and coasting tracks;
// each peak is heard by the nearest track that took a plot this frame, within three of its
// angular sigmas, which then reports the peak's power (otherwise the track is a prediction).
// Estimate::source_present says
// whether any peak passed the threshold; presence_statistic is the strongest peak's statistic (0 when none passed) and
// presence_threshold the threshold.
// Cost: SrpPhat's (srp_phat.h: about 0.1 ms per frame for one source on a 4-microphone
// board) plus the tracker's, tens of microseconds for a few tracks. Not thread-safe.
#pragma once

#include <memory>
#include <vector>

#include "engine/core/estimate.h"
#include "engine/core/status.h"
#include "engine/doa/array_shape.h"
#include "engine/doa/direction_tracker.h"
#include "engine/doa/srp_phat.h"
#include "engine/pipeline/session_config.h"

namespace localizer::engine {

class DirectionStage {
 public:
  // INVALID_ARGUMENT naming the option (a source_side in a planar array's plane, ...).
  static StatusOr<std::unique_ptr<DirectionStage>> Create(const AudioSessionConfig& config);

  const ArrayShapeInfo& shape() const { return srp_.shape(); }

  // One frame (sensors x frame_samples floats, channel-major) at instant t_s: fills e's
  // sources and presence fields.
  void Frame(const float* frame, double t_s, Estimate* e);

 private:
  DirectionStage(SrpPhat srp, DirectionTracker tracker, double peak_sigma_rad)
      : srp_(std::move(srp)), tracker_(std::move(tracker)), peak_sigma_rad_(peak_sigma_rad) {}
  SrpPhat srp_;
  DirectionTracker tracker_;
  double peak_sigma_rad_;
  std::vector<SourceTrack> tracks_;
};

}  // namespace localizer::engine
