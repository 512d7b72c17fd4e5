// Shared by the simulator tests (simulator_test, simulator_echo_noise_test,
// simulator_options_test): the tetra-water array, a still source's options, and the sums the
// tests measure channels with.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "engine/sim/simulator.h"

namespace localizer::engine::testing {

inline constexpr double kSoundSpeed = 1500.0;
inline constexpr double kFs = 11025.0;

// A 2 m tetrahedron centred at 10 m depth (the tetra-water array).
inline ArrayGeometry Tetrahedron(int reference_sensor = 0) {
  const double a = 2.0 / (2.0 * std::sqrt(2.0));
  const Vec3 c(0.0, 0.0, -10.0);
  auto g = ArrayGeometry::Create({c + Vec3(a, a, a), c + Vec3(a, -a, -a), c + Vec3(-a, a, -a), c + Vec3(-a, -a, a)},
                                 kSoundSpeed, reference_sensor);
  EXPECT_TRUE(g.ok()) << g.status().ToString();
  return *g;
}

inline SimOptions Stationary(const Vec3& source_m) {
  SimOptions o;
  o.sample_rate_hz = kFs;
  o.duration_s = 1.0;
  o.band_low_hz = 300.0;
  o.band_high_hz = 3000.0;
  o.snr_db = std::numeric_limits<double>::infinity();
  o.trajectory.position_m = source_m;
  o.seed = 5;
  return o;
}

inline SimResult MustSimulate(const ArrayGeometry& array, const SimOptions& o) {
  StatusOr<SimResult> r = Simulate(array, o);
  EXPECT_TRUE(r.ok()) << r.status().ToString();
  return std::move(r).value();
}

inline std::vector<double> Channel(const SimResult& r, int k) {
  const float* begin = r.samples.data() + k * r.samples_per_channel;
  return std::vector<double>(begin, begin + r.samples_per_channel);
}

inline double MeanPower(const std::vector<double>& x) {
  double sum = 0.0;
  for (double v : x) sum += v * v;
  return sum / static_cast<double>(x.size());
}

// sum_n a[n + lag] b[n] over the overlap: direct O(n) per lag.
inline double CrossCorrelation(const std::vector<double>& a, const std::vector<double>& b, int lag) {
  double sum = 0.0;
  const auto size = static_cast<int>(a.size());
  for (int n = std::max(0, -lag); n < std::min(size, size - lag); ++n) sum += a[n + lag] * b[n];
  return sum;
}

inline SimOptions Clicks(const Vec3& source_m) {
  SimOptions o = Stationary(source_m);
  o.signal = SourceSignal::kClicks;
  o.click_rate_hz = 20.0;
  return o;
}

}  // namespace localizer::engine::testing
