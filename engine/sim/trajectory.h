// Source motion for the simulator: constant velocity, or a constant-rate turn in the
// horizontal (x, y) plane with constant vertical velocity.
//
// Constant turn with rate w (rad/s, positive = counter-clockwise seen from +z), from
// p0, v0 at t = 0:
//     vx(t) = vx0 cos(wt) - vy0 sin(wt),  vy(t) = vx0 sin(wt) + vy0 cos(wt)
//     x(t)  = x0 + (vx0 sin(wt) - vy0 (1 - cos(wt))) / w
//     y(t)  = y0 + (vx0 (1 - cos(wt)) + vy0 sin(wt)) / w
// (w -> 0 reduces to constant velocity). z(t) = z0 + vz0 t. Times in seconds of emission.
#pragma once

#include "engine/core/types.h"

namespace localizer::engine {

struct Trajectory {
  Vec3 position_m = Vec3::Zero();    // at emission time 0
  Vec3 velocity_mps = Vec3::Zero();  // at emission time 0
  double turn_rate_radps = 0.0;      // 0: constant velocity

  Vec3 PositionAt(double t_s) const;
  Vec3 VelocityAt(double t_s) const;
};

}  // namespace localizer::engine
