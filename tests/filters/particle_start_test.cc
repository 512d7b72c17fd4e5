// The first updates after a (re)start: a fix whose position is precise and whose velocity is
// unknown (the session's init_speed_sigma_mps, 2 m/s). One hop later that velocity has
// spread the cloud over decimetres while the frame fixes the position to a fraction of a
// millimetre: a still talker 0.4 m from a 0.45 m tetrahedron in air, pairs measured to
// 0.1 us, 0.17 s hops.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "tests/filters/near_talker_start.h"

namespace localizer::engine {
namespace {

struct StartRun {
  double crlb_m = 0.0;        // per-frame position CRLB at the source
  double worst_m = 0.0;       // largest error over the first second after the start
  double second_m = 0.0;      // error after the second update (the first after a hop)
  double later_rmse_m = 0.0;  // from 1 s to 3 s
};

StartRun RunStart(double tempering, uint64_t noise_seed) {
  const NearTalkerStart scene;
  const auto& [array, source, fs, hop_s, sigma_s, fix_cov] = scene;
  // 0: the first updates in 4 equal stages; 2 m/s, the session's init_speed_sigma_mps.
  const std::unique_ptr<ParticleFilter> pf = scene.Start(tempering, 2.0);
  if (!pf) return {};  // Start has already failed the test
  std::mt19937_64 rng(noise_seed);
  StartRun out;
  out.crlb_m = std::sqrt(fix_cov.trace());
  const int frames = static_cast<int>(3.0 / hop_s) + 1;
  double se = 0.0;
  int later = 0;
  for (int f = 0; f < frames; ++f) {
    const double t = f * hop_s;
    if (f > 0) pf->Predict(hop_s);
    const auto report = pf->Update(MakeMeasurement(array, source, Vec3::Zero(), t, sigma_s, fs, rng));
    EXPECT_TRUE(report.ok());
    const double e = (pf->State().mean.head<3>() - source).norm();
    if (f == 1) out.second_m = e;
    if (t <= 1.0) {
      out.worst_m = std::max(out.worst_m, e);
    } else {
      se += e * e;
      ++later;
    }
  }
  out.later_rmse_m = std::sqrt(se / later);
  return out;
}

// Measured (seeds 1-3): after the second update 1.5, 83 and 1.7 x the per-frame CRLB (with
// the first updates' proposals, particle_set.h ProposeAroundFixes; 2.6-22 x with ESS-chosen
// stages alone: seed 2's first update, no hop from the fix, pulls its velocities through the
// delay-rate term and its prior is 5.5 sds from the fix, outside the proposal's gate),
// nothing worse in the first second, then 0.64-1.03 x from 1 to 3 s. With the first updates
// in 4 equal stages only (progressive correction: the former start, and what tempering off
// still does; printed) seeds 2 and 3 run off along range: 2400 and 450 x after the second
// update, 10500 and 3000 x within the first second.
TEST(ParticleFilterStart, AnUnknownVelocityDoesNotCarryTheFixAway) {
  for (uint64_t seed : {1u, 2u, 3u}) {
    const StartRun run = RunStart(0.05, seed), fixed = RunStart(0.0, seed);
    std::printf(
        "seed %llu: crlb %.3g m; second update %.3g m (%.1f x), worst in the first second %.3g m (%.1f x), "
        "rmse 1-3 s %.3g m (%.2f x)\n",
        static_cast<unsigned long long>(seed), run.crlb_m, run.second_m, run.second_m / run.crlb_m, run.worst_m,
        run.worst_m / run.crlb_m, run.later_rmse_m, run.later_rmse_m / run.crlb_m);
    std::printf("  with 4 equal stages: second update %.1f x, worst in the first second %.1f x\n",
                fixed.second_m / fixed.crlb_m, fixed.worst_m / fixed.crlb_m);
    EXPECT_LT(run.worst_m, 100.0 * run.crlb_m) << "seed " << seed;
    EXPECT_LT(run.later_rmse_m, 1.5 * run.crlb_m) << "seed " << seed;
  }
}

}  // namespace
}  // namespace localizer::engine
