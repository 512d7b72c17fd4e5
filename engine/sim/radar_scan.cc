#include "engine/sim/radar_scan.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <random>
#include <string>

namespace localizer::engine {
namespace {

constexpr double kPi = std::numbers::pi;

// A stream tag of its own, apart from seeding.h's (which belong to the acoustic simulator).
constexpr uint32_t kRadarStream = 0x52414441;    // "RADA"
constexpr uint32_t kTargetsStream = 0x54475453;  // "TGTS"

std::mt19937_64 Engine(uint64_t seed, uint32_t stream, int64_t index) {
  const auto u = static_cast<uint64_t>(index);
  std::seed_seq sequence{static_cast<uint32_t>(seed), static_cast<uint32_t>(seed >> 32), stream,
                         static_cast<uint32_t>(u), static_cast<uint32_t>(u >> 32)};
  return std::mt19937_64(sequence);
}

double Wrap(double a) { return std::remainder(a, 2.0 * kPi); }

Status Bad(const char* field, double v, const char* why) {
  return InvalidArgument(std::string(field) + " is " + std::to_string(v) + ", " + why);
}

}  // namespace

double RadarScanOptions::AreaM2() const {
  const double r1 = OuterRangeM();
  return kPi * (r1 * r1 - min_range_m * min_range_m);
}

Status RadarScanOptions::Validate() const {
  if (!(rotation_rpm > 0.0 && std::isfinite(rotation_rpm))) return Bad("rotation_rpm", rotation_rpm, "must be > 0");
  if (!(prf_hz > 0.0 && std::isfinite(prf_hz))) return Bad("prf_hz", prf_hz, "must be > 0");
  if (!(min_range_m >= 0.0)) return Bad("min_range_m", min_range_m, "must be >= 0");
  if (!(OuterRangeM() > min_range_m) || !std::isfinite(max_range_m))
    return Bad("max_range_m", max_range_m, "must exceed min_range_m");
  if (!(range_sigma_m >= 0.0 && std::isfinite(range_sigma_m)))
    return Bad("range_sigma_m", range_sigma_m, "must be >= 0");
  if (!(bearing_sigma_rad >= 0.0 && bearing_sigma_rad <= 1.0))
    return Bad("bearing_sigma_rad", bearing_sigma_rad, "must be in [0, 1]");
  if (!(detection_probability >= 0.0 && detection_probability <= 1.0))
    return Bad("detection_probability", detection_probability, "must be in [0, 1]");
  if (!(clutter_density_per_m2 >= 0.0 && std::isfinite(clutter_density_per_m2)))
    return Bad("clutter_density_per_m2", clutter_density_per_m2, "must be >= 0");
  if (clutter_density_per_m2 * AreaM2() > 1e7)
    return Bad("clutter_density_per_m2", clutter_density_per_m2, "gives over 1e7 false plots per scan");
  if (!sensor_position_m.allFinite()) return InvalidArgument("sensor_position_m is not finite");
  return Status::Ok();
}

StatusOr<RadarScanSimulator> RadarScanSimulator::Create(const RadarScanOptions& options,
                                                        std::vector<RadarTarget> targets) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  return RadarScanSimulator(options, std::move(targets));
}

RadarScanFrame RadarScanSimulator::Frame(int64_t k) const {
  const RadarScanOptions& o = options_;
  const double t = static_cast<double>(k) * o.period_s();
  const double r0 = o.min_range_m, r1 = o.OuterRangeM();
  std::mt19937_64 engine = Engine(o.seed, kRadarStream, k);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  RadarScanFrame frame;
  frame.scan.time_s = t;
  frame.scan.sensor_position_m = o.sensor_position_m;
  struct Tagged {
    Detection d;
    int64_t source;
  };
  std::vector<Tagged> plots;
  for (const RadarTarget& target : targets_) {
    Eigen::Vector3d p = target.trajectory.PositionAt(t);
    Eigen::Vector3d v = target.trajectory.VelocityAt(t);
    p.z() = o.sensor_position_m.z();
    v.z() = 0.0;
    const Eigen::Vector2d rel = (p - o.sensor_position_m).head<2>();
    const double range = rel.norm();
    // Draw the detection and noise for every target, covered or not, so that one target's
    // draws do not depend on whether another is in coverage.
    const double u = uniform(engine);
    const double nr = normal(engine), nb = normal(engine);
    if (range < r0 || range > r1) continue;
    frame.truth.push_back({target.id, p, v});
    if (u >= o.detection_probability) continue;
    Detection d;
    d.range_m = std::max(range + o.range_sigma_m * nr, 1e-3);
    d.bearing_rad = Wrap(std::atan2(rel.y(), rel.x()) + o.bearing_sigma_rad * nb);
    plots.push_back({d, static_cast<int64_t>(target.id)});
  }
  const double mean_clutter = o.clutter_density_per_m2 * o.AreaM2();
  if (mean_clutter > 0.0) {
    std::poisson_distribution<long> count(mean_clutter);
    const long n = count(engine);
    for (long i = 0; i < n; ++i) {
      Detection d;
      d.range_m = std::sqrt(r0 * r0 + (r1 * r1 - r0 * r0) * uniform(engine));
      d.bearing_rad = Wrap(kPi * (2.0 * uniform(engine) - 1.0));
      plots.push_back({d, -1});
    }
  }
  std::sort(plots.begin(), plots.end(),
            [](const Tagged& a, const Tagged& b) { return a.d.bearing_rad < b.d.bearing_rad; });
  frame.scan.detections.reserve(plots.size());
  frame.source.reserve(plots.size());
  for (const Tagged& p : plots) {
    frame.scan.detections.push_back(p.d);
    frame.source.push_back(p.source);
  }
  return frame;
}

std::vector<RadarTarget> SeedCaseTargets() {
  RadarTarget t;
  t.id = 1;
  t.trajectory.position_m = {1000.0, 1000.0, 0.0};
  t.trajectory.velocity_mps = {-10.0, 0.0, 0.0};
  return {t};
}

std::vector<RadarTarget> RingTargets(int n, double radius_m, double speed_mps, const Eigen::Vector2d& centre_m) {
  std::vector<RadarTarget> out;
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * kPi * i / n;
    RadarTarget t;
    t.id = static_cast<uint64_t>(i) + 1;
    t.trajectory.position_m = {centre_m.x() + radius_m * std::cos(a), centre_m.y() + radius_m * std::sin(a), 0.0};
    t.trajectory.velocity_mps = {-speed_mps * std::sin(a), speed_mps * std::cos(a), 0.0};
    out.push_back(t);
  }
  return out;
}

std::vector<RadarTarget> CrossingTargets(int n, double radius_m, double speed_mps, double arc_rad,
                                         const Eigen::Vector2d& crossing_m) {
  std::vector<RadarTarget> out;
  for (int i = 0; i < n; ++i) {
    const double a = kPi + (n > 1 ? arc_rad * (static_cast<double>(i) / (n - 1) - 0.5) : 0.0);
    const Eigen::Vector2d dir(std::cos(a), std::sin(a));
    RadarTarget t;
    t.id = static_cast<uint64_t>(i) + 1;
    t.trajectory.position_m << crossing_m + radius_m * dir, 0.0;
    t.trajectory.velocity_mps << -speed_mps * dir, 0.0;
    out.push_back(t);
  }
  return out;
}

std::vector<RadarTarget> RandomTargets(int n, double min_range_m, double max_range_m, double min_separation_m,
                                       uint64_t seed) {
  std::mt19937_64 engine = Engine(seed, kTargetsStream, n);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::vector<RadarTarget> out;
  const double sep2 = min_separation_m * min_separation_m;
  for (int attempts = 0; static_cast<int>(out.size()) < n && attempts < 1000 * n; ++attempts) {
    const double r = std::sqrt(min_range_m * min_range_m +
                               (max_range_m * max_range_m - min_range_m * min_range_m) * uniform(engine));
    const double b = 2.0 * kPi * uniform(engine);
    const double heading = 2.0 * kPi * uniform(engine);
    const double speed = 50.0 + 250.0 * uniform(engine);
    const double turn = (1.0 + 2.0 * uniform(engine)) * kPi / 180.0 * (uniform(engine) < 0.5 ? -1.0 : 1.0);
    const Eigen::Vector3d p(r * std::cos(b), r * std::sin(b), 0.0);
    bool clear = true;
    for (const RadarTarget& o : out) {
      if ((o.trajectory.position_m - p).squaredNorm() < sep2) {
        clear = false;
        break;
      }
    }
    if (!clear) continue;
    RadarTarget t;
    t.id = out.size() + 1;
    t.trajectory.position_m = p;
    t.trajectory.velocity_mps = {speed * std::cos(heading), speed * std::sin(heading), 0.0};
    t.trajectory.turn_rate_radps = (out.size() % 5 == 4) ? turn : 0.0;
    out.push_back(t);
  }
  return out;
}

}  // namespace localizer::engine
