#include "engine/sim/trajectory.h"

#include <cmath>

namespace localizer::engine {
namespace {

// sin(x)/x and (1 - cos x)/x for x = w t, so that the turn formulas read
//     x(t) = x0 + t (vx0 S - vy0 C),  y(t) = y0 + t (vx0 C + vy0 S)
// and stay exact as w -> 0 instead of dividing by w.
struct TurnTerms {
  double sin_over_x;            // S
  double one_minus_cos_over_x;  // C
};

TurnTerms TurnTermsAt(double x) {
  // Below 1e-4 rad the Taylor series to x^4 (resp. x^5) is exact to double precision and
  // avoids 0/0 at x = 0.
  if (std::abs(x) < 1e-4) {
    const double x2 = x * x;
    return {1.0 - x2 / 6.0 + x2 * x2 / 120.0, x * (0.5 - x2 / 24.0 + x2 * x2 / 720.0)};
  }
  // From the half angle: sin x = 2 sin(x/2) cos(x/2) and 1 - cos x = 2 sin^2(x/2), which
  // avoids the cancellation in 1 - cos x and costs one sincos.
  const double half_sin = std::sin(0.5 * x);
  const double half_cos = std::cos(0.5 * x);
  return {2.0 * half_sin * half_cos / x, 2.0 * half_sin * half_sin / x};
}

}  // namespace

Vec3 Trajectory::PositionAt(double t_s) const {
  const TurnTerms k = TurnTermsAt(turn_rate_radps * t_s);
  const double vx0 = velocity_mps.x();
  const double vy0 = velocity_mps.y();
  return Vec3(position_m.x() + t_s * (vx0 * k.sin_over_x - vy0 * k.one_minus_cos_over_x),
              position_m.y() + t_s * (vx0 * k.one_minus_cos_over_x + vy0 * k.sin_over_x),
              position_m.z() + t_s * velocity_mps.z());
}

Vec3 Trajectory::VelocityAt(double t_s) const {
  const double angle_rad = turn_rate_radps * t_s;
  const double c = std::cos(angle_rad);
  const double s = std::sin(angle_rad);
  const double vx0 = velocity_mps.x();
  const double vy0 = velocity_mps.y();
  return Vec3(vx0 * c - vy0 * s, vx0 * s + vy0 * c, velocity_mps.z());
}

}  // namespace localizer::engine
