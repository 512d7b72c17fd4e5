// The density of an alpha-stable law, which has no closed form: computed by numerical
// integration (Zolotarev's integral, in Nolan's form) and tabulated once, for likelihoods.
//
// Parameterisation: Nolan's S1, as engine/sim/alpha_stable.h (which draws the variates).
// For X ~ S1(a, b, 1, 0) with 1 < a < 2 (Nolan 1997, "Numerical calculation of stable
// densities and distribution functions", Theorem 1, there in S0; X is S0 shifted by
// zeta = -b tan(pi a / 2), which makes the S1 form below simpler):
//     theta0 = atan(b tan(pi a / 2)) / a
//     V(th; b) = cos(a theta0)^(1/(a-1)) (cos th / sin(a (theta0 + th)))^(a/(a-1))
//                * cos(a theta0 + (a-1) th) / cos th,        th in (-theta0, pi/2)
//     f(x) = a / (pi (a-1) x) * Int_{-theta0}^{pi/2} g(th) exp(-g(th)) d th,
//            g(th) = x^(a/(a-1)) V(th; b),                    for x > 0
//     f(x; b) = f(-x; -b)                                      for x < 0
//     f(0) = Gamma(1 + 1/a) cos(theta0) / (pi (1 + zeta^2)^(1/(2a)))
// g decreases across the range from +inf (to 0; for b = -1 to a positive value, the short
// tail), so g e^-g is a single bump with its top (1/e) where g = 1; the integral is split
// there (found by bisection) and each side is integrated by adaptive Simpson to a relative
// 1e-10. It is evaluated in phi = pi/2 - th, where every factor that vanishes at an end of
// the range is a sine of a small argument, free of cancellation. ~0.1 ms per x; against
// Nolan's pdf table (scipy's copy, alpha 1.1..1.9, all beta) the worst relative error is 1e-9.
// a = 2 is N(d, 2 g^2), in closed form. a <= 1 is not supported (the experiments need
// a = 1.7; a < 1 flips the monotonicity of V and a = 1 has another formula). Within 1e-6
// of 0, f(0) stands for f(x) (closer in, the bump squeezes against an end of the range).
//
// StableDensityTable tabulates ln f of the standard law on u in [-60, 60], step 0.02, and
// interpolates linearly in ln f (error in ln f below 1e-4 for a = 1.7). Beyond u = +-60
// a tail with mass, (1 -+ b) > 1e-9, decays as the asymptotic power |u|^-(1+a), scaled to
// meet the table; a tail without (b = +-1 on the short side, which decays faster than any
// exponential) holds the table's last value, floored at ln f = -700 (an over-estimate,
// harmless in a likelihood). Lookups are O(1), branch-light and thread-safe (const).
// Standard tables are cached per (alpha, beta) for the life of the process (a mutex guards
// the cache), so only the first Create of a law pays for the quadrature.
#pragma once

#include <memory>
#include <vector>

#include "engine/core/status.h"
#include "engine/sim/alpha_stable.h"

namespace localizer::engine::experiments {

// f(x) of S1(alpha, beta, 1, 0) by the integral above; alpha in (1, 2), |beta| <= 1.
// Slow (see above): for building tables and for tests.
double StableStandardDensity(double x, double alpha, double beta);

class StableDensityTable {
 public:
  // INVALID_ARGUMENT naming the field when `params` fails AlphaStable::Validate() or has
  // alpha <= 1. Builds the standard table on first use of (alpha, beta) (a = 2: none):
  // about 0.5 s for 1 < a < 2; later calls share it.
  static StatusOr<StableDensityTable> Create(const AlphaStable& params);

  // ln f(x) of S1(alpha, beta, scale, location), x in the variate's units (f in 1/units).
  double LogDensity(double x) const;
  const AlphaStable& params() const { return params_; }

 private:
  explicit StableDensityTable(const AlphaStable& params) : params_(params) {}
  double StandardLogDensity(double u) const;

  AlphaStable params_;
  double log_scale_ = 0.0;
  // ln f(u_min + i * step) of the standard law, shared by every table of that (a, b).
  std::shared_ptr<const std::vector<double>> log_f_;
  double right_tail_power_ = 0.0;  // 1 + alpha where the right tail has mass, else 0
  double left_tail_power_ = 0.0;
};

}  // namespace localizer::engine::experiments
