#include "engine/sim/propagation.h"

#include <algorithm>
#include <cmath>

namespace localizer::engine {
namespace {

// Speed < c/2 at least halves the error per step: 60 steps take any initial error (the travel
// time) below 1e6 s down to 1e-12 s.
constexpr int kMaxEmissionIterations = 60;

}  // namespace

Emission SolveEmission(const Trajectory& trajectory, const Vec3& sensor_m, double sound_speed_mps,
                       double reception_time_s, double initial_guess_s) {
  double te_s = initial_guess_s;
  double range_m = 0.0;
  for (int i = 0; i < kMaxEmissionIterations; ++i) {
    range_m = (trajectory.PositionAt(te_s) - sensor_m).norm();
    const double next_s = reception_time_s - range_m / sound_speed_mps;
    const bool converged = std::abs(next_s - te_s) < kEmissionTolerance_s;
    te_s = next_s;
    if (converged) break;
  }
  // The range consistent with the returned te, to well below a nanometre.
  return {te_s, (reception_time_s - te_s) * sound_speed_mps};
}

Trajectory MirrorInHorizontalPlane(const Trajectory& trajectory, double plane_z_m) {
  Trajectory image = trajectory;
  image.position_m.z() = 2.0 * plane_z_m - trajectory.position_m.z();
  image.velocity_mps.z() = -trajectory.velocity_mps.z();
  return image;
}

double Speed(const Trajectory& trajectory) { return trajectory.velocity_mps.norm(); }

double MaxTravelTimeBound(const std::vector<Trajectory>& sources, const std::vector<Vec3>& sensors_m,
                          double sound_speed_mps, double duration_s) {
  double range0_m = 0.0;
  double speed_mps = 0.0;
  for (const Trajectory& source : sources) {
    speed_mps = std::max(speed_mps, Speed(source));
    for (const Vec3& m : sensors_m) {
      range0_m = std::max(range0_m, (source.position_m - m).norm());
    }
  }
  return (range0_m + speed_mps * duration_s) / (sound_speed_mps - speed_mps);
}

}  // namespace localizer::engine
