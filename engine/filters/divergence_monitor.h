// Online consistency test that tells when a tracker has lost its target.
//
// Three tests; any reports divergence:
//  - wholesale: the sum of the normalised innovations squared (NIS) over the last `window`
//    updates (or fewer, from 3, right after a reset: a track lost at once need not wait for
//    the window to fill). For a consistent filter it is chi-square with sum(dof) degrees of
//    freedom; divergence when the sum exceeds that distribution's quantile at `confidence`
//    (Wilson-Hilferty, good to ~1 % for dof >= 3) times `slack`, which absorbs the peak
//    likelihood's clipping and the occasional echo;
//  - persistent bias (when per-pair signed innovations z are given): a pair whose mean z over
//    its last `window` used frames exceeds 3 in magnitude. Noise alone gives the mean a
//    standard deviation of 1/sqrt(window) (0.35 for 8: 3 is 8.5 of them); z is capped at 6
//    by the caller, so fewer than window/2 outliers of one sign cannot trip it;
//  - a run: a pair at the cap (|z| >= 5.9) with one sign on its last 3 used frames. A pair
//    the track cannot explain at all; an echo winning a pair now and then (or on alternate
//    sides) does not make a run. On a 4-sensor array the other pairs may agree with the
//    wrong track exactly, so this is often the only early sign.
#pragma once

#include <deque>
#include <utility>
#include <vector>

namespace localizer::engine {

class DivergenceMonitor {
 public:
  explicit DivergenceMonitor(int window = 8, double confidence = 0.999, double slack = 4.0)
      : window_(window), confidence_(confidence), slack_(slack) {}

  // Records one update; returns true when the window says the filter diverged (the windows
  // are then cleared so a reset is judged afresh). `z`: per pair, signed anchored
  // innovations (NaN for pairs not used); empty skips the bias test.
  bool Add(double nis, int dof, const std::vector<double>& z = {});
  void Reset() {
    entries_.clear();
    pair_z_.clear();
  }
  // The current window's NIS sum over its bound (> 1 means divergence when full).
  double ratio() const;

 private:
  int window_;
  double confidence_;
  double slack_;
  std::deque<std::pair<double, int>> entries_;
  std::vector<std::deque<double>> pair_z_;  // per pair, its last `window` used z
};

// Quantile of the chi-square distribution with `dof` degrees of freedom at probability p.
double ChiSquareQuantile(double p, int dof);

}  // namespace localizer::engine
