// Onsets: frames whose in-band power (SrpPhat::band_power) did not fall below the quietest
// frame of the recent past by more than allowed.
//
// rise_db = 10 log10(P_t / min{P_s : t - memory_s <= s < t}); onset() when
// rise_db >= min_rise_db. The first frame is an onset (nothing was heard before it).
// DirectionTracker uses min_rise_db 0: a new track may start only where the power did not
// fall, because when a sound stops its direct path ends first and its reflections linger
// and rise relative to it (direction_tracker.h, "Which peaks start tracks"). A positive
// threshold (tried: 1 dB, the first frame of each rise only) missed sources that start
// late in a frame, whose power rise spreads over two overlapping frames, and lost 4-7 % of
// the sounding talker-frames in tests/bench/doa_room_report.
// Not thread-safe; deterministic; O(memory frames) per frame.
#pragma once

#include <deque>

#include "engine/core/status.h"

namespace localizer::engine {

struct OnsetOptions {
  double min_rise_db = 0.0;       // finite
  double memory_s = 0.05;         // the recent past, >= frame_period_s
  double frame_period_s = 0.016;  // hop / sample rate

  Status Validate() const;  // INVALID_ARGUMENT naming the option
};

class OnsetDetector {
 public:
  static StatusOr<OnsetDetector> Create(const OnsetOptions& options);

  // One frame's power (>= 0, finite; else INVALID_ARGUMENT). Sets rise_db() and onset().
  Status Push(double band_power);
  double rise_db() const { return rise_db_; }  // +inf on the first frame or after silence
  bool onset() const { return onset_; }

 private:
  explicit OnsetDetector(const OnsetOptions& options);
  OnsetOptions options_;
  size_t memory_frames_ = 1;
  std::deque<double> past_;  // the last memory_frames_ powers, oldest first
  double rise_db_ = 0.0;
  bool onset_ = false;
};

}  // namespace localizer::engine
