// Deleter: which tracks end after a scan (Stone Soup's deleter role), by three rules read
// from the track's history (track_history.h) and its position covariance:
//   kUnconfirmable  a tentative track that can no longer reach M hits in its first N scans
//                   (MofN::Unreachable: clutter rarely repeats near a prediction);
//   kCoasted        a confirmed track with max_coast_scans misses in a row;
//   kDiverged       any track whose largest position variance exceeds max_position_sigma_m^2
//                   (a track coasting without measurements grows until it is useless).
// Judge() returns the first rule that applies, in that order, or kKeep. Call it after the
// scan's Record and the initiator's Confirm, so that a track confirmed on this scan is
// judged as confirmed. Stateless besides its options; deterministic.
#pragma once

#include "engine/tws/track_history.h"

namespace localizer::engine::tws {

struct DeleterOptions {
  int confirm_hits = 3;                  // M of the M-of-N confirmation (initiator.h)
  int confirm_window = 5;                // N
  int max_coast_scans = 5;               // >= 1
  double max_position_sigma_m = 2000.0;  // > 0
};

enum class Deletion { kKeep, kUnconfirmable, kCoasted, kDiverged };
const char* DeletionName(Deletion d);  // "keep" | "unconfirmable" | "coasted" | "diverged"

class Deleter {
 public:
  explicit Deleter(const DeleterOptions& options);

  // Inline: called for every track on every scan.
  Deletion Judge(const TrackHistory& history, double largest_position_variance_m2) const {
    if (!history.confirmed) {
      if (rule_.Unreachable(history)) return Deletion::kUnconfirmable;
    } else if (history.misses >= options_.max_coast_scans) {
      return Deletion::kCoasted;
    }
    if (largest_position_variance_m2 > max_variance_m2_) return Deletion::kDiverged;
    return Deletion::kKeep;
  }

  const DeleterOptions& options() const { return options_; }

 private:
  DeleterOptions options_;
  MofN rule_;
  double max_variance_m2_;
};

}  // namespace localizer::engine::tws
