// Adaptive tempering (ParticleFilterOptions::tempering_ess_fraction): a likelihood far
// narrower than the predicted cloud. A still talker 0.4 m from a 0.45 m tetrahedron in air,
// pairs measured to 0.1 us (what a front end with the source's band gives), tracked with
// the session's 1 m/s^2 white acceleration: between 0.17 s frames that acceleration spreads
// the cloud over ~15 mm, while a frame fixes the position to about a third of a millimetre.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "tests/filters/near_talker_start.h"

namespace localizer::engine {
namespace {

struct SharpRun {
  double rmse_m = 0.0;      // after the first second
  double crlb_m = 0.0;      // per-frame position CRLB at the source
  double worst_m = 0.0;     // largest error after the first second
  double median_ess = 0.0;  // of the updates after the first second
};

SharpRun RunSharp(double tempering, uint64_t noise_seed) {
  // A session's start: a fix one bound off on every axis, its spread the bound, speed unknown.
  const NearTalkerStart scene;
  const auto& [array, source, fs, hop_s, sigma_s, fix_cov] = scene;
  const std::unique_ptr<ParticleFilter> pf = scene.Start(tempering, 0.5);
  if (!pf) return {};  // Start has already failed the test
  std::mt19937_64 rng(noise_seed);
  SharpRun out;
  out.crlb_m = std::sqrt(fix_cov.trace());
  double se = 0.0;
  int scored = 0;
  std::vector<double> ess;
  const int frames = static_cast<int>(8.0 / hop_s);
  for (int f = 0; f < frames; ++f) {
    const double t = f * hop_s;
    if (f > 0) pf->Predict(hop_s);
    const auto report = pf->Update(MakeMeasurement(array, source, Vec3::Zero(), t, sigma_s, fs, rng));
    EXPECT_TRUE(report.ok());
    if (t < 1.0) continue;
    const double e = (pf->State().mean.head<3>() - source).norm();
    se += e * e;
    out.worst_m = std::max(out.worst_m, e);
    ess.push_back(report->ess);
    ++scored;
  }
  out.rmse_m = std::sqrt(se / scored);
  std::nth_element(ess.begin(), ess.begin() + ess.size() / 2, ess.end());
  out.median_ess = ess[ess.size() / 2];
  return out;
}

// Measured (seeds 1-3, with the start's proposals, particle_set.h ProposeAroundFixes):
// with tempering at 0.05, RMSE 0.56-0.78 x the per-frame CRLB, the worst frame 1.1-1.8 x,
// median ESS 396-458; without it (printed) seeds 1 and 3 now hold as well (0.60-0.81 x:
// the shared start's velocity std is 0.5 m/s here) and seed 2's cloud collapses onto one or
// two particles every frame: RMSE 6.3 mm, 37 x the bound.
TEST(ParticleFilterTempering, ASharpLikelihoodIsFollowedWithoutCollapsingTheCloud) {
  for (uint64_t seed : {1u, 2u, 3u}) {
    const SharpRun on = RunSharp(0.05, seed), off = RunSharp(0.0, seed);
    std::printf(
        "seed %llu: crlb %.3g m; tempered rmse %.3g m (worst %.3g, median ESS %.0f); untempered rmse %.3g m "
        "(worst %.3g, median ESS %.0f)\n",
        static_cast<unsigned long long>(seed), on.crlb_m, on.rmse_m, on.worst_m, on.median_ess, off.rmse_m, off.worst_m,
        off.median_ess);
    EXPECT_LT(on.rmse_m, 1.5 * on.crlb_m) << "seed " << seed;
    EXPECT_LT(on.worst_m, 5.0 * on.crlb_m) << "seed " << seed;
    EXPECT_GT(on.median_ess, 0.05 * 4096) << "seed " << seed;
  }
}

}  // namespace
}  // namespace localizer::engine
