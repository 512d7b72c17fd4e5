#include "engine/sim/alpha_stable.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <numbers>
#include <string>

#include "engine/sim/invalid_value.h"

namespace localizer::engine {
namespace {

constexpr double kPi = std::numbers::pi;

using sim_detail::Invalid;

// (k + 1/2) 2^-52 for the top 52 bits k of one engine output: in [2^-53, 1 - 2^-53], never
// 0 or 1, and exact (k + 1/2 fits a double's 53-bit mantissa).
double OpenUniform(std::mt19937_64& engine) {
  const uint64_t k = engine() >> 12;
  return (static_cast<double>(k) + 0.5) * 0x1p-52;
}

}  // namespace

Status AlphaStable::Validate() const {
  if (!(alpha > 0.0 && alpha <= 2.0)) return Invalid("alpha", alpha, "must be in (0, 2]");
  if (!(beta >= -1.0 && beta <= 1.0)) return Invalid("beta", beta, "must be in [-1, 1]");
  if (!(scale > 0.0 && std::isfinite(scale))) {
    return Invalid("scale", scale, "must be positive and finite");
  }
  if (!std::isfinite(location)) return Invalid("location", location, "must be finite");
  return Status::Ok();
}

double SampleAlphaStable(const AlphaStable& params, double u_uniform_0_1, double w_exponential) {
  const double a = params.alpha;
  const double b = params.beta;
  const double g = params.scale;
  const double v = kPi * (u_uniform_0_1 - 0.5);  // uniform on (-pi/2, pi/2)
  const double w = w_exponential;
  if (a == 1.0) {
    const double half_pi_bv = 0.5 * kPi + b * v;
    const double x = (2.0 / kPi) * (half_pi_bv * std::tan(v) - b * std::log(0.5 * kPi * w * std::cos(v) / half_pi_bv));
    return g * x + (2.0 / kPi) * b * g * std::log(g) + params.location;
  }
  const double zeta = b * std::tan(0.5 * kPi * a);
  const double shift = std::atan(zeta) / a;                     // B
  const double stretch = std::pow(1.0 + zeta * zeta, 0.5 / a);  // S
  const double av = a * (v + shift);
  const double x =
      stretch * std::sin(av) / std::pow(std::cos(v), 1.0 / a) * std::pow(std::cos(v - av) / w, (1.0 - a) / a);
  return g * x + params.location;
}

double SampleAlphaStable(const AlphaStable& params, std::mt19937_64& engine) {
  const double u = OpenUniform(engine);
  const double w = -std::log(OpenUniform(engine));  // exponential, mean 1; >= 1.1e-16
  return SampleAlphaStable(params, u, w);
}

}  // namespace localizer::engine
