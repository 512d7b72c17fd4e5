// Alpha-stable random variates: heavy-tailed (impulsive) noise for the simulator, drawn by
// the Chambers-Mallows-Stuck method (Chambers, Mallows & Stuck 1976, JASA 71:340; in the
// form corrected by Weron 1996, Stat. Probab. Lett. 28:165).
//
// Parameterisation: Nolan's S1 (Samorodnitsky & Taqqu's S(alpha, beta, gamma, delta); the
// "Z1" of Nolan's tables and scipy.stats.levy_stable's default "S1"). X ~ S1(a, b, g, d) has
// characteristic function E exp(itX) =
//     a != 1:  exp(-g^a |t|^a [1 - i b sign(t) tan(pi a / 2)] + i d t)
//     a == 1:  exp(-g |t| [1 + i b (2 / pi) sign(t) ln|t|] + i d t)
// with alpha a in (0, 2] (tail index: P(|X| > x) ~ x^-a, no variance below 2, no mean at or
// below 1), beta b in [-1, 1] (skew; +1 puts the heavy tail on the right for a < 2),
// scale g > 0 and location d, both in the units of X.
//   - a = 2 is Gaussian N(d, 2 g^2): the variance is 2 g^2, not g^2 (beta has no effect).
//   - a = 1, b = 0 is Cauchy with median d and half-width g; a = 1, b != 0 is skewed.
//   - For a != 1, (X - d) / g ~ S1(a, b, 1, 0). For a = 1 and b != 0 scale is not a pure
//     scale: g * S1(1, b, 1, 0) + d ~ S1(1, b, g, d + (2 / pi) b g ln g).
//   - For a > 1, d is the mean. S1 is discontinuous in a at a = 1 when b != 0: the mode of
//     S1(a, b, g, d) is near d + b g tan(pi a / 2), which diverges as a -> 1 (for a = 1.1,
//     b = 1, g = 1, d = 0 the median is -5.8), so use S0 below to vary a across 1 smoothly.
// Converting to Nolan's S0 (continuous in all four parameters, location near the mode), with
// the same a, b, g:
//     a != 1:  d0 = d1 + b g tan(pi a / 2)
//     a == 1:  d0 = d1 + b (2 / pi) g ln g
// i.e. to draw S0(a, b, g, d0), set location = d0 - b g tan(pi a / 2) (or d0 - b (2/pi) g ln g).
//
// The transform, with V = pi (u - 1/2) uniform on (-pi/2, pi/2) and W exponential, mean 1:
//   a != 1:  B = atan(b tan(pi a / 2)) / a,  S = (1 + b^2 tan^2(pi a / 2))^(1 / (2a)),
//            X = S sin(a (V + B)) / cos(V)^(1/a) * (cos(V - a (V + B)) / W)^((1 - a) / a),
//            result g X + d.
//   a == 1:  X = (2/pi) [(pi/2 + b V) tan V - b ln((pi/2) W cos V / (pi/2 + b V))],
//            result g X + (2/pi) b g ln g + d.
// It is exact (no series or tables); accuracy is that of libm's trig, pow and log.
// Cost: about ten transcendental calls, roughly 0.1-0.2 us per draw on one core; no
// allocation, no state, thread-safe (the engine overload mutates only its engine).
#pragma once

#include <random>

#include "engine/core/status.h"

namespace localizer::engine {

struct AlphaStable {
  double alpha = 2.0;     // tail index, 0 < alpha <= 2 (2: Gaussian)
  double beta = 0.0;      // skewness, -1 <= beta <= 1
  double scale = 1.0;     // gamma > 0, units of the variate
  double location = 0.0;  // delta (S1), finite, units of the variate

  // INVALID_ARGUMENT naming the field and its value when a parameter is out of range or
  // not finite; OK otherwise.
  Status Validate() const;
};

// One S1(alpha, beta, scale, location) variate from a uniform u in (0, 1) and an
// exponential (mean 1) w > 0, by the transform above: deterministic, so a caller can test
// it or supply its own uniforms. `params` must pass Validate(); u outside the open
// interval (0, 1) or w <= 0 may give a non-finite result.
double SampleAlphaStable(const AlphaStable& params, double u_uniform_0_1, double w_exponential);

// The same, drawing u and w from `engine` (two 64-bit outputs per variate). u and w are
// built from the engine's bits by fixed arithmetic (not std:: distributions), so a seed
// gives the same variates on every platform and standard library.
double SampleAlphaStable(const AlphaStable& params, std::mt19937_64& engine);

}  // namespace localizer::engine
