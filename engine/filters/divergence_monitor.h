// Online consistency test that tells when a tracker has lost its target.
//
// Sums the normalised innovation squared (NIS) of the last `window` updates. For a
// consistent filter the sum is chi-square with sum(dof) degrees of freedom; the monitor
// reports divergence when the sum exceeds that distribution's quantile at `confidence`
// (Wilson–Hilferty approximation, good to ~1 % for dof >= 3) times `slack`, which absorbs
// the peak likelihood's clipping and the occasional reflection. The window must be full.
#pragma once

#include <deque>
#include <utility>

namespace localizer::engine {

class DivergenceMonitor {
 public:
  explicit DivergenceMonitor(int window = 8, double confidence = 0.999, double slack = 4.0)
      : window_(window), confidence_(confidence), slack_(slack) {}

  // Records one update; returns true when the window's NIS says the filter diverged
  // (the window is then cleared so a reset is judged afresh).
  bool Add(double nis, int dof);
  void Reset() { entries_.clear(); }
  // The current window's NIS sum over its bound (> 1 means divergence when full).
  double ratio() const;

 private:
  int window_;
  double confidence_;
  double slack_;
  std::deque<std::pair<double, int>> entries_;
};

// Quantile of the chi-square distribution with `dof` degrees of freedom at probability p.
double ChiSquareQuantile(double p, int dof);

}  // namespace localizer::engine
