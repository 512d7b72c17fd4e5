#include "engine/pipeline/innovation_consistency.h"

#include <algorithm>
#include <cmath>

#include "engine/filters/divergence_monitor.h"

namespace localizer::engine {

void InnovationConsistency::Add(double nis, int pairs, const std::vector<UpdateReport::NisTerm>& terms) {
  if (pairs <= 0 || !std::isfinite(nis) || nis < 0.0) return;
  const int slot = count_ % kFrames;
  nis_[static_cast<size_t>(slot)] = nis;
  pairs_[static_cast<size_t>(slot)] = pairs;
  terms_[static_cast<size_t>(slot)] = terms;
  ++count_;
}

double InnovationConsistency::Inflation() const {
  const int held = std::min(count_, kFrames);
  double nis = 0.0;
  int pairs = 0;
  bool with_terms = true;
  for (int k = 0; k < held; ++k) {
    nis += nis_[static_cast<size_t>(k)];
    pairs += pairs_[static_cast<size_t>(k)];
    with_terms &= static_cast<int>(terms_[static_cast<size_t>(k)].size()) == pairs_[static_cast<size_t>(k)];
  }
  if (pairs <= 0) return 1.0;
  const double ratio = std::max(1.0, nis / pairs);
  const double dof = pairs;
  if (!with_terms || nis <= ChiSquareQuantile(0.99, pairs)) return ratio;
  // sum e^2 / (noise + k state) falls with k: bisect on log k for the value `pairs`.
  const auto excess = [&](double k) {
    double sum = 0.0;
    for (int f = 0; f < held; ++f) {
      for (const UpdateReport::NisTerm& t : terms_[static_cast<size_t>(f)]) {
        const double var = t.noise_var_s2 + k * t.predicted_var_s2;
        sum += var > 0.0 ? t.innovation2_s2 / var : 0.0;
      }
    }
    return sum - dof;
  };
  if (excess(kMaxInflation) > 0.0) return std::max(ratio, kMaxInflation);
  double lo = 0.0, hi = std::log(kMaxInflation);
  for (int it = 0; it < 30; ++it) {
    const double mid = 0.5 * (lo + hi);
    (excess(std::exp(mid)) > 0.0 ? lo : hi) = mid;
  }
  return std::max(ratio, std::exp(hi));
}

}  // namespace localizer::engine
