#include "engine/experiments/mixture_noise.h"

#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "engine/experiments/experiment_random.h"
#include "engine/sim/invalid_value.h"

namespace localizer::engine::experiments {

Status MixtureNoise::Validate() const {
  if (!(gaussian_probability >= 0.0 && gaussian_probability <= 1.0)) {
    return sim_detail::Invalid("gaussian_probability", gaussian_probability, "must be in [0, 1]");
  }
  if (!(gaussian_sigma_m > 0.0 && std::isfinite(gaussian_sigma_m))) {
    return sim_detail::Invalid("gaussian_sigma_m", gaussian_sigma_m, "must be positive and finite");
  }
  return stable.Validate();
}

Eigen::Vector2d SampleMixtureNoise(const MixtureNoise& noise, std::mt19937_64& engine) {
  Eigen::Vector2d n;
  for (int axis = 0; axis < 2; ++axis) {
    const bool gaussian = OpenUniform(engine) < noise.gaussian_probability;
    n[axis] = gaussian ? noise.gaussian_sigma_m * StandardNormal(engine) : SampleAlphaStable(noise.stable, engine);
  }
  return n;
}

StatusOr<MixtureDensity> MixtureDensity::Create(const MixtureNoise& noise) {
  LOCALIZER_RETURN_IF_ERROR(noise.Validate());
  StatusOr<StableDensityTable> stable = StableDensityTable::Create(noise.stable);
  if (!stable.ok()) return stable.status();
  return MixtureDensity(noise, std::move(*stable));
}

MixtureDensity::MixtureDensity(const MixtureNoise& noise, StableDensityTable stable)
    : noise_(noise), stable_(std::move(stable)) {
  const double e = noise.gaussian_probability;
  log_gaussian_weight_ = std::log(e) - std::log(noise.gaussian_sigma_m * std::sqrt(2.0 * std::numbers::pi));
  log_stable_weight_ = std::log1p(-e);
}

double MixtureDensity::LogDensity(double n_m) const {
  const double z = n_m / noise_.gaussian_sigma_m;
  const double log_gaussian = log_gaussian_weight_ - 0.5 * z * z;
  const double log_stable = log_stable_weight_ + stable_.LogDensity(n_m);
  // log(exp(a) + exp(b)) without overflow; one of the two may be -inf (e = 0 or 1).
  const double high = std::max(log_gaussian, log_stable);
  const double low = std::min(log_gaussian, log_stable);
  if (high == -std::numeric_limits<double>::infinity()) return high;
  return high + std::log1p(std::exp(low - high));
}

}  // namespace localizer::engine::experiments
