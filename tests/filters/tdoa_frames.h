// Synthetic TDOA frames for the particle filter's tests: a regular tetrahedron and the
// delays a frame measures for a source moving at constant velocity, with Gaussian noise; and
// the options the per-particle motion tests share.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "engine/array/array_geometry.h"
#include "engine/core/measurement.h"
#include "engine/filters/particle_filter.h"

namespace localizer::engine {

// The per-particle motion tests' filter (turn rates, speed changes): 4096 particles, a fixed
// TDOA noise of 8 us, seed 42; the motion itself is the defaults'.
inline ParticleFilterOptions PersistentMotionOptions() {
  ParticleFilterOptions o;
  o.particles = 4096;
  o.tdoa_sigma_s = 8e-6;
  o.seed = 42;
  return o;
}

inline ArrayGeometry Tetrahedron(double edge_m, const Vec3& centre, double c) {
  const double a = edge_m / (2.0 * std::sqrt(2.0));
  auto g = ArrayGeometry::Create(
      {centre + Vec3(a, a, a), centre + Vec3(a, -a, -a), centre + Vec3(-a, a, -a), centre + Vec3(-a, -a, a)}, c);
  EXPECT_TRUE(g.ok());
  return *g;
}

// TDOAs a frame centred at t_s measures for a source at p0 + v t: pair k describes the
// instant t_s - d_k / 2 (solved by fixed-point iteration), plus Gaussian noise.
inline Measurement MakeMeasurement(const ArrayGeometry& array, const Vec3& p0, const Vec3& v, double t_s,
                                   double sigma_s, double fs, std::mt19937_64& rng) {
  std::normal_distribution<double> noise(0.0, sigma_s);
  Measurement m;
  m.t_s = t_s;
  m.sample_rate_hz = fs;
  for (int p = 0; p < array.pair_count(); ++p) {
    double d = array.Tdoa(p0 + v * t_s)(p);
    for (int it = 0; it < 3; ++it) d = array.Tdoa(p0 + v * (t_s - d / 2))(p);
    PairMeasurement pm;
    pm.sensor = array.sensor_of_pair(p);
    pm.delay_s = d + noise(rng);
    pm.quality = 10.0;
    pm.peak_snr = 40.0;  // a clearly detected source
    m.pairs.push_back(pm);
  }
  return m;
}

}  // namespace localizer::engine
