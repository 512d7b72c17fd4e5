// A still talker 0.41 m from a 0.45 m tetrahedron in air, pairs measured to 0.1 us at 48 kHz
// in 8192-sample hops, tracked by a particle filter started from a fix one bound off on every
// axis: a likelihood far narrower than the cloud (particle_tempering_test, particle_start_test).
#pragma once

#include <gtest/gtest.h>

#include <memory>

#include "engine/array/multilateration.h"
#include "engine/filters/particle_filter.h"
#include "tests/filters/tdoa_frames.h"

namespace localizer::engine {

struct NearTalkerStart {
  const ArrayGeometry array = Tetrahedron(0.45, Vec3::Zero(), 343.0);
  const Vec3 source = Vec3(0.25, -0.2, 0.25);  // 0.41 m from the centre
  const double fs = 48000.0, hop_s = 8192.0 / 48000.0, sigma_s = 1e-7;
  const Mat3 fix_cov = TdoaPositionCrlb(array, source, sigma_s);  // the per-frame bound

  // 4096 particles, the session's 1 m/s^2 white acceleration, a fixed TDOA noise, seed 7,
  // started from the fix with velocity std speed_sigma_mps.
  std::unique_ptr<ParticleFilter> Start(double tempering_ess_fraction, double speed_sigma_mps) const {
    ParticleFilterOptions o;
    o.particles = 4096;
    o.accel_noise_mps2 = 1.0;
    o.tdoa_sigma_s = sigma_s;
    o.tempering_ess_fraction = tempering_ess_fraction;
    o.seed = 7;
    auto pf = ParticleFilter::Create(array, o);
    EXPECT_TRUE(pf.ok());
    if (!pf.ok()) return nullptr;
    TrackState belief;
    belief.mean.head<3>() = source + fix_cov.diagonal().cwiseSqrt();
    belief.covariance.topLeftCorner<3, 3>() = fix_cov;
    belief.covariance.bottomRightCorner<3, 3>() = speed_sigma_mps * speed_sigma_mps * Mat3::Identity();
    EXPECT_TRUE((*pf)->Initialise(belief).ok());
    return std::move(pf).value();
  }
};

}  // namespace localizer::engine
