// The seed's impulsive measurement noise: on each axis independently, with probability e a
// Gaussian, otherwise an alpha-stable variate (engine/sim/alpha_stable.h, Nolan's S1):
//     n = N(0, sigma^2)                          with probability e
//     n ~ S1(alpha, beta, scale, location)       with probability 1 - e
// density p(n) = e phi(n / sigma) / sigma + (1 - e) f_S(n), f_S tabulated (stable_density.h).
//
// The seed's stable part is S1(1.7, 1, 10 m, -3 m). In S1 with alpha > 1 the location is the
// mean (-3 m) but not the centre of the mass: beta = 1 puts the heavy tail on the right
// (P(n > x) ~ x^-1.7) and pushes the bulk left, so its median is -3 + 10 * (-0.331) =
// -6.31 m and its mode -8.9 m (-3 + 10 * -0.594; the S0 location, -8.1 m, is near it).
// The mixture's per-axis mean is (1 - e) * -3 = -1.5 m and its variance infinite: an
// averaging filter is biased and can be thrown arbitrarily far. The seed does not give the Gaussian's sigma;
// the default here is 1 m (the stable part's scale is 10 m), a sensor that is good half of
// the time. Sampling and densities are thread-safe (const; draws mutate only the engine).
#pragma once

#include <Eigen/Core>
#include <random>

#include "engine/core/status.h"
#include "engine/experiments/stable_density.h"
#include "engine/sim/alpha_stable.h"

namespace localizer::engine::experiments {

struct MixtureNoise {
  double gaussian_probability = 0.5;         // e in [0, 1]
  double gaussian_sigma_m = 1.0;             // sigma > 0 (not given by the seed)
  AlphaStable stable{1.7, 1.0, 10.0, -3.0};  // alpha, beta, scale (m), location (m), S1

  // INVALID_ARGUMENT naming the field (gaussian_probability, gaussian_sigma_m, or the
  // stable part's alpha, beta, scale, location).
  Status Validate() const;
};

// One 2-D noise vector: per axis one uniform picks the component, then one Gaussian
// (Box-Muller, experiment_random.h) or one stable draw; 4 to 6 engine outputs per axis.
Eigen::Vector2d SampleMixtureNoise(const MixtureNoise& noise, std::mt19937_64& engine);

class MixtureDensity {
 public:
  // Validate()'s errors, and INVALID_ARGUMENT when the stable alpha is <= 1 (no table).
  static StatusOr<MixtureDensity> Create(const MixtureNoise& noise);

  // ln p(n) of one axis, n in m (p in 1/m); finite for every finite n.
  double LogDensity(double n_m) const;
  // ln p(n_x) + ln p(n_y): the axes are independent.
  double LogDensity(const Eigen::Vector2d& n_m) const { return LogDensity(n_m.x()) + LogDensity(n_m.y()); }
  const MixtureNoise& noise() const { return noise_; }

 private:
  MixtureDensity(const MixtureNoise& noise, StableDensityTable stable);

  MixtureNoise noise_;
  StableDensityTable stable_;
  double log_gaussian_weight_;  // ln(e / (sigma sqrt(2 pi))), -inf for e = 0
  double log_stable_weight_;    // ln(1 - e), -inf for e = 1
};

}  // namespace localizer::engine::experiments
