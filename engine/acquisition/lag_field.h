// One frame's GCC functions as a detection field over lags: each pair's GCC divided by
// its noise-only standard deviation, and max-filtered copies of it for searches over
// cells of positions.
//
// Noise-only scale: with independent noise on the two channels, each lag of a PHAT GCC is
// approximately N(0, sigma_R^2) with sigma_R = 1 / sqrt(2 * in-band bins); the front end
// reports it implicitly as peak_value / peak_snr (measurement.h). Normalised values
//     n_p(lag) = g_p(lag) / sigma_R,p
// are N(0, 1) per lag without a source, whatever the frame size, band or weighting, so the
// sum over pairs at the lags a position predicts, divided by sqrt(pairs), is a detection
// statistic with a known null distribution (presence.h).
//
// Level l holds the running maximum over |lag - i| <= 2^l - 1 (doubling: M_{l+1}[i] =
// max(M_l[i - 2^l], M_l[i + 2^l]), clamped at the window's ends): an upper bound of n_p
// over a cell whose lags span that half-width.
// A pair is usable when the frame kept its GCC (GccOptions::keep_gcc) and its peak is
// positive; unusable pairs read as 0 (no evidence either way).
// Pairs 0..reference_pairs() - 1 are the measurement's reference pairs (its order); the
// measurement's cross pairs (Measurement::cross_pairs, two non-reference sensors) follow,
// usable when they hold energy in the band. A cross pair (a, b) at a position reads the lag
// lag_b - lag_a of the reference pairs of sensors b and a.
#pragma once

#include <cstddef>
#include <vector>

#include "engine/core/measurement.h"

namespace localizer::engine {

class LagField {
 public:
  // Builds the normalised field from `m`, and its max-filter levels when `with_levels`
  // (O(window x levels) per pair; MaxAround needs them).
  void Build(const Measurement& m, bool with_levels = true);

  int pair_count() const { return static_cast<int>(pairs_.size()); }  // reference and cross
  int usable_pairs() const { return usable_; }                        // reference and cross
  int reference_pairs() const { return reference_pairs_; }
  int usable_reference_pairs() const { return usable_reference_; }
  // Pair p >= reference_pairs(): its sensors a and b (Measurement::cross_pairs).
  int cross_sensor_a(int p) const { return pairs_[static_cast<std::size_t>(p)].sensor_a; }
  int cross_sensor_b(int p) const { return pairs_[static_cast<std::size_t>(p)].sensor_b; }
  bool usable(int p) const { return pairs_[p].usable; }
  double sample_rate_hz() const { return sample_rate_hz_; }
  // Normalised GCC of pair p at a fractional lag (samples), linear between integer lags;
  // 0 outside the pair's window or when unusable.
  double At(int p, double lag_samples) const;
  // Pair p's normalised GCC at its integer lags first_lag(p)..last_lag(p) (one value, 0, when
  // unusable): what At interpolates.
  const std::vector<float>& values(int p) const { return pairs_[p].levels[0]; }
  // Upper bound of the normalised GCC over [lag - half_width, lag + half_width] (samples).
  double MaxAround(int p, double lag_samples, double half_width_samples) const;
  // The lag (samples, refined by a parabola through the integer maximum and its neighbours)
  // of the largest normalised value within [lo, hi]; false when the window misses the pair's.
  bool ArgMax(int p, double lo_samples, double hi_samples, double* lag_samples, double* value) const;
  // The pair's lag window in samples [first, last].
  int first_lag(int p) const { return pairs_[p].first_lag; }
  int last_lag(int p) const { return pairs_[p].first_lag + static_cast<int>(pairs_[p].levels[0].size()) - 1; }

 private:
  struct Pair {
    bool usable = false;
    int first_lag = 0;
    int sensor_a = -1, sensor_b = -1;        // a cross pair's sensors
    std::vector<std::vector<float>> levels;  // levels[0] = n_p, then max-filtered
  };
  // Fills `pair` from a GCC window and its noise scale 1 / sigma_R (0: unusable).
  void BuildPair(const std::vector<float>& gcc, int first_lag, double inv_sigma, bool with_levels, Pair* pair);
  std::vector<Pair> pairs_;
  int usable_ = 0;
  int reference_pairs_ = 0;
  int usable_reference_ = 0;
  double sample_rate_hz_ = 0.0;
};

}  // namespace localizer::engine
