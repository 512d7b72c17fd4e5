// Track-while-scan scenarios: a rotating search radar (or a scanning sonar) and targets in
// the x-y plane; one engine::Scan of plots per revolution, with the truth of that instant.
//
// Radar (the seed's): 33 rpm, so one revolution every 60/33 = 1.8182 s; PRF 1800 Hz, which
// sets the unambiguous range c / (2 PRF) = 83.3 km, the default outer edge of the
// surveillance region (an annulus min_range_m .. max_range_m around the sensor, all
// bearings).
// Scan k describes the instant t_k = k T (T the period). The plots of a revolution are all
// stamped t_k and the truth is taken at t_k: the within-revolution skew (a plot at bearing
// theta is really seen theta / 2 pi of a revolution later) is not modelled, so that the
// truth and the tracker's scan time describe the same instant.
// Plots:
//   target  each target inside the annulus is detected with probability P_D; its plot is
//           range = |p - s| + N(0, sigma_r^2), bearing = atan2 + N(0, sigma_t^2), wrapped to
//           (-pi, pi], with s the sensor position (targets at the sensor's height);
//   clutter Poisson count with mean density * area(annulus), each uniform in area over the
//           annulus (r = sqrt(U(r0^2, r1^2)), theta = U(-pi, pi)).
// The plots of a scan are sorted by bearing (a rotating antenna reports them in that order),
// so that their order carries no hint of which is a target.
// Draws: scan k's plots come from an engine keyed by (seed, k): scans replay alone.
// Truth per scan: id, position and velocity of every target inside the annulus.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "engine/core/detection.h"
#include "engine/core/status.h"
#include "engine/sim/trajectory.h"

namespace localizer::engine {

struct RadarScanOptions {
  double rotation_rpm = 33.0;  // scan period 60 / rpm seconds
  double prf_hz = 1800.0;      // max_range_m defaults to c / (2 PRF)
  double min_range_m = 200.0;
  double max_range_m = 0.0;  // 0: the unambiguous range, 83275 m at 1800 Hz
  double range_sigma_m = 10.0;
  double bearing_sigma_rad = 0.01;      // 0.57 degrees
  double detection_probability = 0.9;   // P_D in [0, 1]
  double clutter_density_per_m2 = 0.0;  // false plots per m^2 per scan, >= 0
  Eigen::Vector3d sensor_position_m = Eigen::Vector3d::Zero();
  uint64_t seed = 1;

  double period_s() const { return 60.0 / rotation_rpm; }
  double OuterRangeM() const { return max_range_m > 0.0 ? max_range_m : 299792458.0 / (2.0 * prf_hz); }
  double AreaM2() const;
  Status Validate() const;  // INVALID_ARGUMENT naming the field
};

struct RadarTarget {
  uint64_t id = 0;
  Trajectory trajectory;  // z ignored: targets move in the sensor's horizontal plane
};

struct TargetTruth {
  uint64_t id = 0;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();
};

struct RadarScanFrame {
  Scan scan;
  std::vector<TargetTruth> truth;
  std::vector<int64_t> source;  // per plot: the target id, or -1 for clutter
};

class RadarScanSimulator {
 public:
  static StatusOr<RadarScanSimulator> Create(const RadarScanOptions& options, std::vector<RadarTarget> targets);
  // Scan k (k >= 0) at t = k T; deterministic in (options, targets, k).
  RadarScanFrame Frame(int64_t k) const;
  const RadarScanOptions& options() const { return options_; }
  const std::vector<RadarTarget>& targets() const { return targets_; }

 private:
  RadarScanSimulator(const RadarScanOptions& options, std::vector<RadarTarget> targets)
      : options_(options), targets_(std::move(targets)) {}
  RadarScanOptions options_;
  std::vector<RadarTarget> targets_;
};

// The seed's case: one target from (1000 m, 1000 m) at -10 m/s along x.
std::vector<RadarTarget> SeedCaseTargets();
// n targets evenly spaced on a circle of radius_m around `centre_m`, each moving at
// speed_mps at right angles to its radius (counter-clockwise): neighbours stay about
// 2 radius sin(pi / n) apart for a while (they drift apart slowly).
std::vector<RadarTarget> RingTargets(int n, double radius_m, double speed_mps, const Eigen::Vector2d& centre_m);
// n targets on an arc of arc_rad (centred on the -x direction) at radius_m from
// `crossing_m`, all heading for it at speed_mps: they meet there at t = radius / speed,
// neighbours crossing at arc / (n - 1) radians.
std::vector<RadarTarget> CrossingTargets(int n, double radius_m, double speed_mps, double arc_rad,
                                         const Eigen::Vector2d& crossing_m);
// n targets placed uniformly in area over the annulus min_range_m .. max_range_m (at least
// min_separation_m apart, by rejection), headings uniform, speeds U(50, 300) m/s; every
// fifth in a coordinated turn of U(1, 3) deg/s, either sense. Seeded.
std::vector<RadarTarget> RandomTargets(int n, double min_range_m, double max_range_m, double min_separation_m,
                                       uint64_t seed);

}  // namespace localizer::engine
