// A coasting track's velocity decay (TwsOptions::coast_velocity_decay_s): the contract is
// the linear map v -> a v with a = exp(-dt / tau) per missed scan, so a track that stops
// hearing its target comes to rest about |v| tau from its last update; 0 keeps the
// constant-velocity coast.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "engine/tws/tws_tracker.h"

namespace localizer::engine::tws {
namespace {

struct Coast {
  Eigen::Vector3d last_hit_velocity;  // the track's velocity after its last update
  Eigen::Vector3d last_hit_position;
  Eigen::Vector3d position;  // after the misses
  Eigen::Vector3d velocity;
  double velocity_variance = 0.0;  // its x-x velocity variance after the misses
};

// A target at 3 m/s along x, plotted every 0.1 s with 0.05 m of seeded noise for 30 scans,
// then not plotted for `misses` scans.
Coast CoastAfter(double decay_s, int misses) {
  TwsOptions options;
  options.dimensions = 2;
  options.accel_noise_mps2 = 1.0;
  options.max_coast_scans = 100;
  options.coast_velocity_decay_s = decay_s;
  auto tracker = TwsTracker::Create(options);
  EXPECT_TRUE(tracker.ok());
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 0.05);
  const double dt = 0.1;
  Coast c;
  for (int k = 0; k < 30 + misses; ++k) {
    std::vector<CartesianPlot> plots;
    if (k < 30) {
      CartesianPlot p;
      p.position_m = Eigen::Vector3d(3.0 * k * dt + noise(rng), noise(rng), 0.0);
      p.covariance_m2 = 0.05 * 0.05 * Eigen::Matrix3d::Identity();
      plots.push_back(p);
    }
    EXPECT_TRUE((*tracker)->ProcessCartesian(k * dt, plots).ok());
    const std::vector<TrackReport> tracks = (*tracker)->Tracks(true);
    EXPECT_EQ(tracks.size(), 1u);
    if (tracks.empty()) return c;
    if (k == 29) c.last_hit_velocity = tracks[0].velocity_mps, c.last_hit_position = tracks[0].position_m;
    c.position = tracks[0].position_m;
    c.velocity = tracks[0].velocity_mps;
    c.velocity_variance = tracks[0].covariance(3, 3);
  }
  return c;
}

TEST(Coasting, VelocityDecaysByExpMinusDtOverTauPerMiss) {
  const double tau = 0.3, dt = 0.1;
  const int misses = 20;  // 2 s
  const Coast decayed = CoastAfter(tau, misses), constant = CoastAfter(0.0, misses);
  // The same plots: the same track up to its last update.
  EXPECT_NEAR((decayed.last_hit_velocity - constant.last_hit_velocity).norm(), 0.0, 1e-12);
  EXPECT_NEAR(decayed.last_hit_velocity.x(), 3.0, 0.5);
  // Velocity: a^misses of the last update's.
  const double a = std::exp(-dt / tau);
  EXPECT_NEAR((decayed.velocity - std::pow(a, misses) * decayed.last_hit_velocity).norm(), 0.0, 1e-9);
  // Position: the first prediction uses the full velocity, each later one a times the last:
  // v dt (1 + a + ... + a^(misses-1)) = v dt (1 - a^misses) / (1 - a), about v (tau + dt/2).
  const double travelled = (decayed.position - decayed.last_hit_position).x();
  const double expected = decayed.last_hit_velocity.x() * dt * (1.0 - std::pow(a, misses)) / (1.0 - a);
  EXPECT_NEAR(travelled, expected, 1e-9);
  EXPECT_LT(travelled, decayed.last_hit_velocity.x() * (tau + dt));
  // Without the decay it coasts on at its velocity: v x 2 s.
  EXPECT_NEAR((constant.position - constant.last_hit_position).x(), constant.last_hit_velocity.x() * misses * dt,
              1e-9);
  EXPECT_NEAR((constant.velocity - constant.last_hit_velocity).norm(), 0.0, 1e-12);
  // The velocity's uncertainty shrinks with it (a^2 per miss, plus the process noise), not grows.
  EXPECT_LT(decayed.velocity_variance, constant.velocity_variance);
}

TEST(Coasting, ANegativeDecayIsRefusedByName) {
  TwsOptions options;
  options.coast_velocity_decay_s = -1.0;
  const Status s = options.Validate();
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("coast_velocity_decay_s"), std::string::npos);
}

}  // namespace
}  // namespace localizer::engine::tws
