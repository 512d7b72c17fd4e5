#include "engine/tws/chi_square.h"

#include <cmath>
#include <numbers>

namespace localizer::engine::tws {

double ChiSquareCdf(int dof, double x) {
  if (x <= 0.0) return 0.0;
  const double h = 0.5 * x;
  // P(k/2, h) by the recurrences P(a + 1, h) = P(a, h) - h^a e^-h / Gamma(a + 1), starting
  // from P(1/2, h) = erf(sqrt h) (odd k) or P(1, h) = 1 - e^-h (even k).
  double p = 0.0;
  double a = 0.0;
  double term = 0.0;  // h^a e^-h / Gamma(a + 1)
  if (dof % 2 == 1) {
    p = std::erf(std::sqrt(h));
    a = 0.5;
    term = std::sqrt(h) * std::exp(-h) / std::tgamma(1.5);
  } else {
    p = 1.0 - std::exp(-h);
    a = 1.0;
    term = h * std::exp(-h);  // Gamma(2) = 1
  }
  for (int i = 0; a + i < 0.5 * dof - 1e-9; ++i) {  // k = a, a + 1, ... (exact: a is 1/2 or 1)
    p -= term;
    term *= h / (a + i + 1.0);
  }
  return p;
}

double ChiSquareQuantile(int dof, double probability) {
  if (dof == 2) return -2.0 * std::log1p(-probability);
  double lo = 0.0;
  double hi = 1.0;
  while (ChiSquareCdf(dof, hi) < probability) hi *= 2.0;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    (ChiSquareCdf(dof, mid) < probability ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

}  // namespace localizer::engine::tws
