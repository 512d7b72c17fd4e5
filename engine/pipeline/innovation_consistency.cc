#include "engine/pipeline/innovation_consistency.h"

#include <algorithm>
#include <cmath>

namespace localizer::engine {

void InnovationConsistency::Add(double nis, int pairs) {
  if (pairs <= 0 || !std::isfinite(nis) || nis < 0.0) return;
  const int slot = count_ % kFrames;
  nis_[static_cast<size_t>(slot)] = nis;
  pairs_[static_cast<size_t>(slot)] = pairs;
  ++count_;
}

double InnovationConsistency::Inflation() const {
  const int held = std::min(count_, kFrames);
  double nis = 0.0;
  int pairs = 0;
  for (int k = 0; k < held; ++k) {
    nis += nis_[static_cast<size_t>(k)];
    pairs += pairs_[static_cast<size_t>(k)];
  }
  return pairs > 0 ? std::max(1.0, nis / pairs) : 1.0;
}

}  // namespace localizer::engine
