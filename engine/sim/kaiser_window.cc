#include "engine/sim/kaiser_window.h"

#include <cmath>

namespace localizer::engine {

double BesselI0(double x) {
  // I0(x) = sum_k ((x/2)^k / k!)^2: every term is positive, so summing until the terms stop
  // changing the sum is accurate.
  const double quarter_x2 = 0.25 * x * x;
  double term = 1.0;
  double sum = 1.0;
  for (int k = 1; k < 500; ++k) {
    term *= quarter_x2 / (static_cast<double>(k) * k);
    sum += term;
    if (term < 1e-17 * sum) break;
  }
  return sum;
}

double KaiserWindow(double u, double beta) {
  if (std::abs(u) > 1.0) return 0.0;
  return BesselI0(beta * std::sqrt(1.0 - u * u)) / BesselI0(beta);
}

double KaiserBetaForAttenuation(double attenuation_db) {
  if (attenuation_db > 50.0) return 0.1102 * (attenuation_db - 8.7);
  if (attenuation_db >= 21.0) {
    return 0.5842 * std::pow(attenuation_db - 21.0, 0.4) + 0.07886 * (attenuation_db - 21.0);
  }
  return 0.0;
}

}  // namespace localizer::engine
