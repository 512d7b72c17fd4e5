#include "engine/core/normal_quantile.h"

#include <algorithm>
#include <cmath>

namespace localizer::engine {
namespace {

// log Q(t) for t >= 0, without underflow for t up to ~37 (erfc) and by the asymptotic
// series beyond.
double LogUpperTail(double t) {
  if (t < 37.0) return std::log(0.5 * std::erfc(t / std::sqrt(2.0)));
  return -0.5 * t * t - std::log(t * std::sqrt(2.0 * M_PI)) + std::log1p(-1.0 / (t * t));
}

}  // namespace

double NormalUpperQuantile(double p) {
  p = std::clamp(p, 1e-300, 0.5);
  const double log_p = std::log(p);
  double t = std::sqrt(std::max(0.0, -2.0 * log_p));  // start above the root
  for (int i = 0; i < 60; ++i) {
    const double log_q = LogUpperTail(t);
    // d log Q / dt = -phi(t) / Q(t)
    const double log_phi = -0.5 * t * t - 0.5 * std::log(2.0 * M_PI);
    const double slope = -std::exp(log_phi - log_q);
    const double step = (log_q - log_p) / slope;
    t = std::max(0.0, t - step);
    if (std::abs(step) < 1e-13 * std::max(1.0, t)) break;
  }
  return t;
}

double NormalQuantile(double p) { return p < 0.5 ? -NormalUpperQuantile(p) : NormalUpperQuantile(1.0 - p); }

}  // namespace localizer::engine
