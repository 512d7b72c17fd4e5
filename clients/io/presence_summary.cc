#include "clients/io/presence_summary.h"

#include <cmath>
#include <cstdio>

namespace localizer::io {

void PresenceSummary::Add(const engine::Estimate& e) {
  ++frames;
  if (e.source_present) ++present;
  if (e.ambiguous) ++ambiguous;
  if (e.initialised) ++initialised;
  if (e.initialised && e.far_field) ++far_field;
  if (!(e.presence_threshold > 0.0)) return;
  if (tested == 0 || e.presence_statistic > max_statistic) {
    max_statistic = e.presence_statistic;
    threshold = e.presence_threshold;
  }
  ++tested;
}

std::optional<std::string> PresenceSummary::NoSourceLine() const {
  if (tested == 0 || present > 0) return std::nullopt;
  char line[160];
  std::snprintf(line, sizeof line, "no source found in %llu frames (presence statistic max %.3g, threshold %.3g)",
                static_cast<unsigned long long>(frames), max_statistic, threshold);
  return std::string(line);
}

std::optional<std::string> PresenceSummary::FarFieldLine() const {
  if (far_field == 0) return std::nullopt;
  char line[200];
  std::snprintf(line, sizeof line,
                "range unobservable (far field) in %llu of %llu positions: their direction from the array's centroid "
                "holds, their range does not",
                static_cast<unsigned long long>(far_field), static_cast<unsigned long long>(initialised));
  return std::string(line);
}

}  // namespace localizer::io
