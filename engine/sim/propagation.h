// Sound propagation from a moving source to a fixed sensor: emission times, ranges, images.
//
// The sound heard at sensor m at reception time t left the source at the emission time te
// that solves
//     te + |p(te) - m| / c = t.
// The map te -> t - |p(te) - m| / c is a contraction with factor |v| / c, so fixed-point
// iteration converges geometrically from any start: underwater (|v| / c ~ 1e-3) the error
// falls a thousandfold per step, so from te_0 = t four steps reach 1e-12 s at 20 m. The
// iteration stops when a step moves te by less than kEmissionTolerance_s; the error left is
// then below kEmissionTolerance_s * |v| / (c - |v|).
#pragma once

#include <vector>

#include "engine/core/types.h"
#include "engine/sim/trajectory.h"

namespace localizer::engine {

inline constexpr double kEmissionTolerance_s = 1e-12;

struct Emission {
  double time_s = 0.0;   // te
  double range_m = 0.0;  // |p(te) - m| = c (t - te)
};

// Requires the trajectory's speed to be below half the sound speed (Simulate checks), which
// bounds the iteration count (at most 60). `initial_guess_s` only changes the cost: for
// consecutive samples, extrapolating the previous two emission times is within ~1e-12 s and
// needs one or two steps instead of four.
Emission SolveEmission(const Trajectory& trajectory, const Vec3& sensor_m, double sound_speed_mps,
                       double reception_time_s, double initial_guess_s);
inline Emission SolveEmission(const Trajectory& trajectory, const Vec3& sensor_m, double sound_speed_mps,
                              double reception_time_s) {
  return SolveEmission(trajectory, sensor_m, sound_speed_mps, reception_time_s, reception_time_s);
}

// The trajectory's image in the plane z = plane_z_m (a mirror source for a reflection off
// that plane): x and y unchanged, z' = 2 plane_z_m - z, vz' = -vz. A turn in (x, y) stays a
// turn, so the image is itself a Trajectory.
Trajectory MirrorInHorizontalPlane(const Trajectory& trajectory, double plane_z_m);

// |v|, constant along any Trajectory (a turn rotates v in the (x, y) plane).
double Speed(const Trajectory& trajectory);

// An upper bound on the travel time from any of `sources` to any of `sensors_m` for the
// sound received during [0, duration_s]. With R0 the largest distance at emission time 0 and
// |p(te) - p(0)| <= |v| |te|, the travel time T obeys T <= (R0 + |v| (duration + T)) / c, so
//     T <= (R0 + |v| duration) / (c - |v|).
double MaxTravelTimeBound(const std::vector<Trajectory>& sources, const std::vector<Vec3>& sensors_m,
                          double sound_speed_mps, double duration_s);

}  // namespace localizer::engine
