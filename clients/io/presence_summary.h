// Source presence over a whole run: how many frames held a source, and the one line the
// CLI prints (track, track --server, simulate --server) when none did; and how many
// positions had a range the frame could not bound (Estimate::far_field), with the line
// printed when some did.
//
// A frame counts as tested when its presence threshold is > 0: the engine ran its presence
// test there (engine/core/estimate.h). Estimates from an engine or server that does not
// report presence carry threshold 0 and are not counted, so an older server never makes a
// run look silent.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "engine/core/estimate.h"

namespace localizer::io {

struct PresenceSummary {
  uint64_t frames = 0;         // estimates seen
  uint64_t tested = 0;         // with presence_threshold > 0
  uint64_t present = 0;        // with source_present
  uint64_t ambiguous = 0;      // with ambiguous
  uint64_t initialised = 0;    // with a position
  uint64_t far_field = 0;      // of those, with far_field
  double max_statistic = 0.0;  // largest presence_statistic over the tested frames
  double threshold = 0.0;      // the threshold of the frame with that statistic

  void Add(const engine::Estimate& e);

  // "no source found in N frames (presence statistic max X, threshold Y)" when frames
  // were tested and none held a source; nothing otherwise.
  std::optional<std::string> NoSourceLine() const;
  // "range unobservable (far field) in N of M positions: their direction from the array's
  // centroid holds, their range does not" when some were; nothing otherwise.
  std::optional<std::string> FarFieldLine() const;
};

}  // namespace localizer::io
