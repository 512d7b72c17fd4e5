#include "engine/filters/divergence_monitor.h"

#include <algorithm>
#include <cmath>

#include "engine/core/normal_quantile.h"

namespace localizer::engine {

double ChiSquareQuantile(double p, int dof) {
  const double k = dof, z = NormalQuantile(p);
  const double a = 2.0 / (9.0 * k);
  const double t = 1.0 - a + z * std::sqrt(a);
  return k * t * t * t;
}

bool DivergenceMonitor::Add(double nis, int dof, const std::vector<double>& z) {
  constexpr double kBiasSigmas = 3.0;
  constexpr int kRunFrames = 3;
  constexpr double kRunSigmas = 5.9;  // the caller caps z at 6
  entries_.emplace_back(nis, dof);
  while (static_cast<int>(entries_.size()) > window_) entries_.pop_front();
  bool biased = false;
  if (pair_z_.size() < z.size()) pair_z_.resize(z.size());
  for (size_t p = 0; p < z.size(); ++p) {
    if (std::isnan(z[p])) continue;
    std::deque<double>& w = pair_z_[p];
    w.push_back(z[p]);
    while (static_cast<int>(w.size()) > window_) w.pop_front();
    // A run of extreme innovations of one sign: a pair the track cannot explain at all.
    if (static_cast<int>(w.size()) >= kRunFrames) {
      bool run = true;
      for (size_t i = w.size() - kRunFrames; i < w.size(); ++i)
        run &= std::abs(w[i]) >= kRunSigmas && w[i] * w.back() > 0.0;
      biased |= run;
    }
    if (static_cast<int>(w.size()) < window_) continue;
    double sum = 0.0;
    for (double v : w) sum += v;
    biased |= std::abs(sum / window_) > kBiasSigmas;
  }
  const bool wholesale = static_cast<int>(entries_.size()) >= std::min(window_, 3) && ratio() > 1.0;
  if (!wholesale && !biased) return false;
  Reset();
  return true;
}

double DivergenceMonitor::ratio() const {
  double sum = 0.0;
  int dof = 0;
  for (const auto& [nis, d] : entries_) {
    sum += nis;
    dof += d;
  }
  if (dof == 0) return 0.0;
  return sum / (slack_ * ChiSquareQuantile(confidence_, dof));
}

}  // namespace localizer::engine
