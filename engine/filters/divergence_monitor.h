// Online consistency test that tells when a tracker has lost its target.
//
// Two tests over the last `window` updates; either reports divergence:
//  - wholesale: the sum of the normalised innovations squared (NIS). For a consistent filter
//    it is chi-square with sum(dof) degrees of freedom; divergence when the sum exceeds that
//    distribution's quantile at `confidence` (Wilson-Hilferty, good to ~1 % for dof >= 3)
//    times `slack`, which absorbs the peak likelihood's clipping and the occasional echo;
//  - persistent bias (when per-pair signed innovations z are given): a pair whose mean z over
//    its last `window` used frames exceeds 3 in magnitude. Noise alone gives the mean a
//    standard deviation of 1/sqrt(window) (0.35 for 8: 3 is 8.5 of them); z is capped at 6
//    by the caller, so fewer than window/2 outliers of one sign cannot trip it.
// The windows must be full.
#pragma once

#include <deque>
#include <vector>
#include <utility>

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
