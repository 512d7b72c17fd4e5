#include "engine/acquisition/lag_field.h"

#include <algorithm>
#include <bit>
#include <cmath>

namespace localizer::engine {

void LagField::Build(const Measurement& m, bool with_levels) {
  sample_rate_hz_ = m.sample_rate_hz;
  reference_pairs_ = static_cast<int>(m.pairs.size());
  pairs_.resize(m.pairs.size() + m.cross_pairs.size());
  usable_ = 0;
  for (size_t p = 0; p < m.pairs.size(); ++p) {
    const PairMeasurement& pm = m.pairs[p];
    const bool usable = !pm.gcc.empty() && pm.peak_value > 0.0 && pm.peak_snr > 0.0;
    BuildPair(pm.gcc, pm.first_lag_samples, usable ? pm.peak_snr / pm.peak_value : 0.0, with_levels, &pairs_[p]);
  }
  usable_reference_ = usable_;
  for (size_t q = 0; q < m.cross_pairs.size(); ++q) {
    const CrossPairGcc& cp = m.cross_pairs[q];
    Pair& out = pairs_[m.pairs.size() + q];
    BuildPair(cp.gcc, cp.first_lag_samples, cp.noise_floor_inverse, with_levels, &out);
    out.sensor_a = cp.sensor_a;
    out.sensor_b = cp.sensor_b;
  }
}

void LagField::BuildPair(const std::vector<float>& gcc, int first_lag, double inv_sigma, bool with_levels, Pair* pair) {
  Pair& out = *pair;
  out.first_lag = first_lag;
  out.sensor_a = out.sensor_b = -1;
  out.usable = !gcc.empty() && inv_sigma > 0.0;
  if (!out.usable) {
    out.levels.assign(1, std::vector<float>(std::max<size_t>(gcc.size(), 1), 0.0f));
    return;
  }
  ++usable_;
  const int n = static_cast<int>(gcc.size());
  int level_count = 1;
  while (with_levels && (1 << (level_count - 1)) < n) ++level_count;
  out.levels.resize(static_cast<size_t>(level_count));
  std::vector<float>& base = out.levels[0];
  base.resize(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i)
    base[static_cast<size_t>(i)] = static_cast<float>(gcc[static_cast<size_t>(i)] * inv_sigma);
  for (int l = 1; l < level_count; ++l) {
    const std::vector<float>& prev = out.levels[static_cast<size_t>(l - 1)];
    std::vector<float>& next = out.levels[static_cast<size_t>(l)];
    next.resize(static_cast<size_t>(n));
    const int d = 1 << (l - 1);
    for (int i = 0; i < n; ++i) {
      const float a = prev[static_cast<size_t>(std::max(i - d, 0))];
      const float b = prev[static_cast<size_t>(std::min(i + d, n - 1))];
      next[static_cast<size_t>(i)] = std::max(prev[static_cast<size_t>(i)], std::max(a, b));
    }
  }
}

double LagField::At(int p, double lag_samples) const {
  const Pair& pair = pairs_[static_cast<size_t>(p)];
  if (!pair.usable) return 0.0;
  const std::vector<float>& g = pair.levels[0];
  const double x = lag_samples - pair.first_lag;
  if (!(x >= 0.0) || x > static_cast<double>(g.size() - 1)) return 0.0;
  const size_t i = static_cast<size_t>(x);
  if (i + 1 >= g.size()) return g.back();
  const double f = x - static_cast<double>(i);
  return (1.0 - f) * g[i] + f * g[i + 1];
}

double LagField::MaxAround(int p, double lag_samples, double half_width_samples) const {
  const Pair& pair = pairs_[static_cast<size_t>(p)];
  if (!pair.usable) return 0.0;
  const int n = static_cast<int>(pair.levels[0].size());
  const double lo = lag_samples - half_width_samples - pair.first_lag;
  const double hi = lag_samples + half_width_samples - pair.first_lag;
  if (hi < 0.0 || lo > n - 1) return 0.0;
  const int i_lo = std::max(0, static_cast<int>(std::floor(lo)));
  const int i_hi = std::min(n - 1, static_cast<int>(std::ceil(hi)));
  const int centre = (i_lo + i_hi) / 2;
  const int need = std::max(centre - i_lo, i_hi - centre);  // half-width to cover [i_lo, i_hi]
  // The smallest level l with 2^l - 1 >= need: bit_width(need).
  const int level =
      std::min(static_cast<int>(std::bit_width(static_cast<unsigned>(need))), static_cast<int>(pair.levels.size()) - 1);
  return pair.levels[static_cast<size_t>(level)][static_cast<size_t>(centre)];
}

bool LagField::ArgMax(int p, double lo_samples, double hi_samples, double* lag_samples, double* value) const {
  const Pair& pair = pairs_[static_cast<size_t>(p)];
  if (!pair.usable) return false;
  const std::vector<float>& g = pair.levels[0];
  const int n = static_cast<int>(g.size());
  const int i_lo = std::max(0, static_cast<int>(std::ceil(lo_samples - pair.first_lag)));
  const int i_hi = std::min(n - 1, static_cast<int>(std::floor(hi_samples - pair.first_lag)));
  if (i_lo > i_hi) return false;
  int best = i_lo;
  for (int i = i_lo + 1; i <= i_hi; ++i) {
    if (g[static_cast<size_t>(i)] > g[static_cast<size_t>(best)]) best = i;
  }
  double offset = 0.0;
  if (best > 0 && best < n - 1) {
    const double a = g[static_cast<size_t>(best - 1)], b = g[static_cast<size_t>(best)],
                 c = g[static_cast<size_t>(best) + 1];
    const double denom = a - 2.0 * b + c;
    if (denom < 0.0) offset = std::clamp(0.5 * (a - c) / denom, -0.5, 0.5);
  }
  *lag_samples = pair.first_lag + best + offset;
  *value = g[static_cast<size_t>(best)];
  return true;
}

}  // namespace localizer::engine
