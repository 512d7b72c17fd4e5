#include "engine/acquisition/pair_closure.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace localizer::engine {
namespace {

constexpr double kClosureMargin = 3.0;   // x the consensus's noise-only sd
constexpr double kMinMoveSamples = 2.0;  // a closer consensus is the same peak
constexpr double kMinOwnPeak = 3.0;      // noise sds: the pair's own GCC must show the path
constexpr int kOwnPeakReach = 2;         // samples between the consensus and the pair's own peak

using Witness = PairClosure::Witness;

// Fills `out` with reference pair p's witnesses.
void WitnessesOf(const Measurement& m, const LagField& field, int p, std::vector<Witness>* witnesses) {
  std::vector<Witness>& out = *witnesses;
  out.clear();
  const int sensor = m.pairs[static_cast<size_t>(p)].sensor;
  for (int q = field.reference_pairs(); q < field.pair_count(); ++q) {
    const int a = field.cross_sensor_a(q), b = field.cross_sensor_b(q);
    if (!field.usable(q) || (a != sensor && b != sensor)) continue;
    const int other_sensor = a == sensor ? b : a;
    for (int r = 0; r < field.reference_pairs(); ++r) {
      if (m.pairs[static_cast<size_t>(r)].sensor == other_sensor && field.usable(r)) {
        out.push_back({q, r, b == sensor ? 1.0 : -1.0});
      }
    }
  }
}

double Consensus(const LagField& field, int p, const std::vector<Witness>& witnesses, const std::vector<double>& lags,
                 double x) {
  double s = field.At(p, x);
  for (const Witness& w : witnesses) s += field.At(w.field_pair, w.sign * (x - lags[static_cast<size_t>(w.other)]));
  return s;
}

// The vertex of the parabola through (-1, a), (0, b), (1, c), within half a sample (0 when
// b is not above the chord).
double VertexOffset(double a, double b, double c) {
  const double denom = a - 2.0 * b + c;
  return denom < 0.0 ? std::clamp(0.5 * (a - c) / denom, -0.5, 0.5) : 0.0;
}

// Pair p's own peak within kOwnPeakReach samples of integer lag x: a local maximum of its
// normalised GCC of at least kMinOwnPeak, refined by a parabola; false when there is none.
bool OwnPeakNear(const LagField& field, int p, int x, double* lag_samples) {
  const std::vector<float>& g = field.values(p);
  const int n = static_cast<int>(g.size());
  int best = -1;
  for (int i = std::max(1, x - field.first_lag(p) - kOwnPeakReach);
       i <= std::min(n - 2, x - field.first_lag(p) + kOwnPeakReach); ++i) {
    const size_t k = static_cast<size_t>(i);
    if (g[k] > g[k - 1] && g[k] >= g[k + 1] && g[k] >= kMinOwnPeak &&
        (best < 0 || g[k] > g[static_cast<size_t>(best)])) {
      best = i;
    }
  }
  if (best < 0) return false;
  const size_t k = static_cast<size_t>(best);
  *lag_samples = field.first_lag(p) + best + VertexOffset(g[k - 1], g[k], g[k + 1]);
  return true;
}

}  // namespace

ClosureRepair PairClosure::Repair(Measurement* m) {
  ClosureRepair none;
  if (m == nullptr || m->cross_pairs.empty() || !(m->sample_rate_hz > 0.0)) return none;
  LagField& field = field_;
  field.Build(*m, /*with_levels=*/false);
  const double fs = m->sample_rate_hz;
  std::vector<double>& lags = lags_;
  lags.resize(m->pairs.size());
  for (size_t p = 0; p < m->pairs.size(); ++p) lags[p] = m->pairs[p].delay_s * fs;
  // Each pair's largest normalised value: S_p cannot exceed the sum of its terms' maxima, so a
  // pair whose witnesses read near theirs at its peak cannot be contradicted (no scan needed).
  std::vector<double>& largest = largest_;
  largest.assign(static_cast<size_t>(field.pair_count()), 0.0);
  for (int q = 0; q < field.pair_count(); ++q) {
    if (!field.usable(q)) continue;
    const std::vector<float>& g = field.values(q);
    // At least 0: a lag outside the window reads 0.
    largest[static_cast<size_t>(q)] = std::max(0.0, static_cast<double>(*std::max_element(g.begin(), g.end())));
  }

  ClosureRepair found;
  int contradicted = 0;
  for (int p = 0; p < field.reference_pairs(); ++p) {
    if (!field.usable(p)) continue;
    WitnessesOf(*m, field, p, &witnesses_);
    const std::vector<Witness>& witnesses = witnesses_;
    if (witnesses.size() < 2) continue;
    const double at_peak = Consensus(field, p, witnesses, lags, lags[static_cast<size_t>(p)]);
    const double margin = kClosureMargin * std::sqrt(1.0 + static_cast<double>(witnesses.size()));
    double bound = largest[static_cast<size_t>(p)];
    for (const Witness& w : witnesses) bound += largest[static_cast<size_t>(w.field_pair)];
    if (bound - at_peak <= margin) continue;
    double best = at_peak;
    int best_x = 0;
    for (int x = field.first_lag(p); x <= field.last_lag(p); ++x) {
      if (std::abs(x - lags[static_cast<size_t>(p)]) <= kMinMoveSamples) continue;
      const double s = Consensus(field, p, witnesses, lags, x);
      if (s > best) {
        best = s;
        best_x = x;
      }
    }
    if (best - at_peak <= margin) continue;
    ++contradicted;
    found.pair = p;
    found.from_s = m->pairs[static_cast<size_t>(p)].delay_s;
    found.gain = best - at_peak;
    double lag = 0.0;
    found.own_peak = OwnPeakNear(field, p, best_x, &lag);
    found.sigma_s = 0.0;  // the caller takes it from the own peak's curvature
    if (!found.own_peak) {
      // No path of its own where the others agree (its peak smeared or masked): the
      // consensus's peak, refined by a parabola, read through the witnesses' reference pairs.
      lag = best_x + VertexOffset(Consensus(field, p, witnesses, lags, best_x - 1.0), best,
                                  Consensus(field, p, witnesses, lags, best_x + 1.0));
      double witness_sigma = 0.0;
      for (const Witness& w : witnesses) {
        const double s = m->pairs[static_cast<size_t>(w.other)].delay_sigma_s;
        if (s > 0.0 && (witness_sigma == 0.0 || s < witness_sigma)) witness_sigma = s;
      }
      // A witness's lag and its cross pair's peak, taken as equally precise.
      found.sigma_s = std::sqrt(2.0) * witness_sigma;
      if (!(found.sigma_s > 0.0)) found.pair = -1;
    }
    found.to_s = lag / fs;
  }
  if (contradicted != 1 || found.pair < 0) return none;
  PairMeasurement& pair = m->pairs[static_cast<size_t>(found.pair)];
  pair.delay_s = found.to_s;
  pair.delay_sigma_s = found.sigma_s;
  pair.confirmed = true;
  return found;
}

}  // namespace localizer::engine
