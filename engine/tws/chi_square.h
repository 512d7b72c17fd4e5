// Chi-square quantiles for ellipsoidal gates.
//
// A measurement z with predicted mean zhat and innovation covariance S falls in the gate
// when d^2 = (z - zhat)^T S^-1 (z - zhat) <= g; for Gaussian innovations d^2 ~ chi^2(m),
// m = dim z, so the gate holds the true plot with probability P_G = F_m(g) and
// g = F_m^-1(P_G). Closed form for m = 2 (g = -2 ln(1 - P_G)); otherwise the regularised
// lower incomplete gamma P(m/2, g/2) is inverted by bisection (60 halvings, ~1e-15
// relative). Cost: a few microseconds; computed once per tracker, not per plot.
#pragma once

namespace localizer::engine::tws {

// F_m(x) = P(chi^2(m) <= x), m in 1..6, x >= 0.
double ChiSquareCdf(int dof, double x);

// g with F_m(g) = probability, probability in (0, 1), m in 1..6.
double ChiSquareQuantile(int dof, double probability);

}  // namespace localizer::engine::tws
