// Targets for stating filter accuracy against the posterior CRLB (filter_bounds_test):
// constant velocity, constant acceleration and a coordinated turn, seen by the 8-sensor
// box of manoeuvre_track.h through TDOAs with known Gaussian noise, and the bound itself
// along each target's true path for a filter's own motion model.
//
// Paths (from t = 0, one frame every dt_s, ranges 4-14 m from the array centre):
//   cv    from (-8, -4, 1) m at (1.5, 0.5, 0) m/s
//   ca    from (-8, -4, 1) m at (0.5, 1.5, 0) m/s with (0.3, -0.15, 0) m/s^2
//   turn  from (6, -6, 0.5) m at (0, 2, 0) m/s turning at 0.2 rad/s (radius 10 m)
//   cv-random  cv's start, then the constant-velocity model's own motion: an acceleration
//         ~ N(0, accel_std^2 I3) drawn per frame (seeded) and held over it, so the truth is
//         a draw from the model the CV filters assume and the PCRLB is their expected bound
// TDOAs by manoeuvre_track.h's TdoaFrame: exact delays at the instant the filters model,
// plus N(0, sigma_s^2) from std::mt19937_64(seed).
#pragma once

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "engine/filters/posterior_crlb.h"
#include "tests/filters/manoeuvre_track.h"

namespace localizer::engine::testing {

struct BoundScene {
  std::string path = "cv";      // cv | ca | turn | cv-random
  double accel_std_mps2 = 1.0;  // cv-random's white acceleration (the filters' default)
  double duration_s = 12.0;
  double dt_s = 0.05;
  double sigma_s = 2e-6;
  int steps() const { return static_cast<int>(std::lround(duration_s / dt_s)); }
};

struct PathPoint {
  Vec3 position_m, velocity_mps, accel_mps2;
  double turn_rate_radps = 0.0;
};

inline PathPoint PathAt(const std::string& path, double t) {
  if (path == "ca") {
    const Vec3 p0(-8, -4, 1), v0(0.5, 1.5, 0), a(0.3, -0.15, 0);
    return {p0 + v0 * t + 0.5 * a * t * t, v0 + a * t, a, 0.0};
  }
  if (path == "turn") {
    const double w = 0.2, speed = 2.0, radius = speed / w;
    const Vec3 centre(6.0 - radius, -6.0, 0.5);  // counter-clockwise from (6, -6) heading +y
    const double angle = w * t;
    const Vec3 p = centre + radius * Vec3(std::cos(angle), std::sin(angle), 0.0);
    const Vec3 v = speed * Vec3(-std::sin(angle), std::cos(angle), 0.0);
    return {p, v, -w * w * (p - centre), w};
  }
  const Vec3 p0(-8, -4, 1), v0(1.5, 0.5, 0);
  return {p0 + v0 * t, v0, Vec3::Zero(), 0.0};
}

// The path at t = k dt, k = 0..steps (cv-random drawn from std::mt19937_64(seed)).
inline std::vector<PathPoint> MakePath(const BoundScene& scene, uint64_t seed) {
  std::vector<PathPoint> points;
  if (scene.path != "cv-random") {
    for (int k = 0; k <= scene.steps(); ++k) points.push_back(PathAt(scene.path, k * scene.dt_s));
    return points;
  }
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> accel(0.0, scene.accel_std_mps2);
  PathPoint p = PathAt("cv", 0.0);
  const double dt = scene.dt_s;
  for (int k = 0; k <= scene.steps(); ++k) {
    points.push_back(p);
    const Vec3 a(accel(rng), accel(rng), accel(rng));
    p.position_m += p.velocity_mps * dt + 0.5 * a * dt * dt;
    p.velocity_mps += a * dt;
    p.accel_mps2 = a;
  }
  return points;
}

// The true state in a motion model's layout: (p, v), then a for ca/singer, the turn rate for ct.
inline Eigen::VectorXd TrueStateFor(const std::string& model, const PathPoint& point) {
  const int extra = model == "ca" || model == "singer" ? 3 : model == "ct" ? 1 : 0;
  Eigen::VectorXd x(6 + extra);
  x.head<3>() = point.position_m;
  x.segment<3>(3) = point.velocity_mps;
  if (extra == 3) x.tail<3>() = point.accel_mps2;
  if (extra == 1) x(6) = point.turn_rate_radps;
  return x;
}

// The belief every filter starts from: the truth at t = 0 offset by one std on every
// position and velocity axis (pos_std_m, vel_std_mps).
inline TrackState StartOf(const PathPoint& p, double pos_std_m, double vel_std_mps) {
  TrackState b;
  b.mean.head<3>() = p.position_m + Vec3::Constant(pos_std_m);
  b.mean.tail<3>() = p.velocity_mps - Vec3::Constant(vel_std_mps);
  b.covariance.topLeftCorner<3, 3>() = pos_std_m * pos_std_m * Mat3::Identity();
  b.covariance.bottomRightCorner<3, 3>() = vel_std_mps * vel_std_mps * Mat3::Identity();
  return b;
}

}  // namespace localizer::engine::testing
