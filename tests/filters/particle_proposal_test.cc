// Proposals that look at the measurement (particle_set.h ProposeAroundFixes and
// ProposeLocalFixes): the redrawn cloud still carries the label's predicted density, and a
// talker inside a small 4-sensor array, started as the session restarts (every exact TDOA
// solution as a label, an unknown velocity), is held instead of lost to the far solution.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "engine/array/multilateration.h"
#include "engine/filters/particle_set.h"
#include "tests/filters/tdoa_frames.h"

namespace localizer::engine {
namespace {

// Weighted mean and covariance of the set's positions and velocities, in double.
TrackState WeightedMoments(const ParticleSet& set, int n) {
  const auto cols = set.columns();
  const auto& w = set.weights();
  TrackState s;
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < 6; ++k) s.mean(k) += w[static_cast<size_t>(i)] * cols[static_cast<size_t>(k)][i];
  }
  for (int i = 0; i < n; ++i) {
    Vec6 d;
    for (int k = 0; k < 6; ++k) d(k) = cols[static_cast<size_t>(k)][i] - s.mean(k);
    s.covariance += w[static_cast<size_t>(i)] * d * d.transpose();
  }
  return s;
}

// A cloud as one hop after a start leaves it (a fix's position, 2 m/s of unknown velocity,
// 0.17 s) with half its particles redrawn around a fix 0.1 m off its mean: the weighted
// moments stay the prior's (importance sampling), and the redrawn half sits at the fix.
TEST(ParticleProposal, RedrawnParticlesKeepThePriorsMoments) {
  const ArrayGeometry array = Tetrahedron(0.45, Vec3::Zero(), 343.0);
  ParticleFilterOptions o;
  o.particles = 65536;
  o.seed = 11;
  o.SetSingleMotion();
  ParticleSet set(array, o);
  Mat6 root = Mat6::Zero();
  root.topLeftCorner<3, 3>() = 1e-3 * Mat3::Identity();
  root.bottomRightCorner<3, 3>() = 2.0 * Mat3::Identity();
  set.SampleGaussian(Vec6(0.3, -0.2, 0.1, 0.0, 0.0, 0.0), root);
  set.Predict(0.17, 1.0);
  const TrackState before = WeightedMoments(set, o.particles);
  const Vec3 fix = before.mean.head<3>() + Vec3(0.1, 0.0, 0.0);  // about 0.3 sd off
  const double fix_sd_m = 1e-3;
  set.ProposeAroundFixes({{0, fix, fix_sd_m * fix_sd_m * Mat3::Identity()}}, 0.5);
  const TrackState after = WeightedMoments(set, o.particles);
  int near_fix = 0;
  const auto cols = set.columns();
  for (int i = 0; i < o.particles; ++i) {
    near_fix += (Vec3(cols[0][i], cols[1][i], cols[2][i]) - fix).norm() < 5.0 * fix_sd_m;
  }
  for (int k = 0; k < 6; ++k) {
    const double sd = std::sqrt(before.covariance(k, k));
    // Half the particles carry the prior now: the mean's standard error is about sd / 181.
    EXPECT_NEAR(after.mean(k), before.mean(k), 0.03 * sd) << "component " << k;
    EXPECT_NEAR(std::sqrt(after.covariance(k, k)), sd, 0.05 * sd) << "component " << k;
  }
  // Position and velocity stay correlated as the hop made them (x = x0 + v dt).
  EXPECT_NEAR(after.covariance(0, 3) / before.covariance(0, 3), 1.0, 0.1);
  EXPECT_NEAR(near_fix, o.particles / 2, o.particles / 50);
}

// A talker 0.08 m from the centre of a 0.25 m tetrahedron, still, pairs measured to 0.8 us
// at 48 kHz in 8192-sample hops (campaign scene 19000122, whose track ran off to the far
// exact solution metres away within one hop of every restart). Started as the session
// restarts after divergence: one label per exact solution of the first frame's TDOAs, each
// with the session's 2 m/s velocity prior.
struct InsideTalkerRun {
  double crlb_m = 0.0;
  double rmse_m = 0.0;  // of the heaviest hypothesis, from the second update to 3 s
};

InsideTalkerRun RunInsideTalker(double tempering, uint64_t noise_seed) {
  const ArrayGeometry array = Tetrahedron(0.25, Vec3::Zero(), 343.0);
  const Vec3 source(0.05, -0.05, 0.04);
  const double fs = 48000.0, hop_s = 8192.0 / 48000.0, sigma_s = 0.8e-6;
  ParticleFilterOptions o;
  o.particles = 4096;
  o.tdoa_sigma_s = sigma_s;
  o.tempering_ess_fraction = tempering;
  o.seed = noise_seed;
  auto pf = ParticleFilter::Create(array, o);
  EXPECT_TRUE(pf.ok());
  if (!pf.ok()) return {};
  std::mt19937_64 rng(noise_seed);
  const Measurement first = MakeMeasurement(array, source, Vec3::Zero(), 0.0, sigma_s, fs, rng);
  Eigen::VectorXd tdoa(array.pair_count());
  for (int p = 0; p < array.pair_count(); ++p) tdoa(p) = first.pairs[static_cast<size_t>(p)].delay_s;
  std::vector<WeightedBelief> modes;
  for (const Vec3& candidate : ClosedFormCandidates(array, tdoa)) {
    WeightedBelief b;
    b.belief.mean.head<3>() = candidate;
    b.belief.covariance.topLeftCorner<3, 3>() = TdoaPositionCrlb(array, candidate, sigma_s);
    b.belief.covariance.bottomRightCorner<3, 3>() = 4.0 * Mat3::Identity();
    modes.push_back(b);
  }
  EXPECT_EQ(modes.size(), 2u) << "the scene is meant to have two exact solutions";
  EXPECT_TRUE((*pf)->InitialiseMixture(modes).ok());
  InsideTalkerRun out;
  out.crlb_m = std::sqrt(TdoaPositionCrlb(array, source, sigma_s).trace());
  double se = 0.0;
  int count = 0;
  const int frames = static_cast<int>(3.0 / hop_s) + 1;
  for (int f = 1; f < frames; ++f) {
    (*pf)->Predict(hop_s);
    EXPECT_TRUE((*pf)->Update(MakeMeasurement(array, source, Vec3::Zero(), f * hop_s, sigma_s, fs, rng)).ok());
    const std::vector<WeightedBelief> h = (*pf)->Hypotheses();
    const double e = (h.front().belief.mean.head<3>() - source).norm();
    se += e * e;
    ++count;
  }
  out.rmse_m = std::sqrt(se / count);
  return out;
}

// Measured (seeds 1-3): RMSE of the heaviest hypothesis 0.64-0.97 x the per-frame CRLB.
// With tempering off (no proposals, no ESS-chosen stages; printed) 0.019 m, 0.17 m and 9.2 m
// (41, 370 and 20000 x); the campaign's scene, before the proposals, lost the talker within
// a hop of every restart (ACCURACY.md, "Thirty-third pass").
TEST(ParticleProposal, ATalkerInsideASmallArrayIsNotLostToTheFarSolution) {
  for (uint64_t seed : {1u, 2u, 3u}) {
    const InsideTalkerRun run = RunInsideTalker(0.05, seed), off = RunInsideTalker(0.0, seed);
    std::printf("seed %llu: crlb %.3g m; rmse of the heaviest hypothesis %.3g m (%.2f x); tempering off %.3g m\n",
                static_cast<unsigned long long>(seed), run.crlb_m, run.rmse_m, run.rmse_m / run.crlb_m, off.rmse_m);
    EXPECT_LT(run.rmse_m, 3.0 * run.crlb_m) << "seed " << seed;
  }
}

}  // namespace
}  // namespace localizer::engine
