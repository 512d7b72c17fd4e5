// The particle filter's several hypotheses (particle_set.h "contenders"): a 4-sensor array's
// second exact TDOA solution explains every frame as well as the truth, so it must live (and
// be reported) until the data tell them apart; a mode the data rule out must go.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cstdio>
#include <random>

#include "engine/array/multilateration.h"
#include "engine/filters/particle_filter.h"
#include "engine/filters/particle_set.h"
#include "tests/filters/tdoa_frames.h"

namespace localizer::engine {
namespace {

constexpr double kSampleRateHz = 16000.0;
constexpr double kHopS = 2048.0 / kSampleRateHz;
constexpr double kSigmaS = 2e-6;

struct GhostScene {
  ArrayGeometry array;
  Vec3 truth_m;
  Vec3 ghost_m;
};

// A 20 m tetrahedron in water and a still source 2.5 apertures out, on the first of a fixed
// list of bearings where the three TDOAs have a second exact solution at least 10 m from it.
GhostScene FindGhostScene() {
  GhostScene s{Tetrahedron(20.0, Vec3::Zero(), 1500.0), Vec3::Zero(), Vec3::Zero()};
  for (double az = 0.1; az < 6.2; az += 0.3) {
    for (double el : {-0.6, -0.2, 0.2, 0.6}) {
      const Vec3 truth = 50.0 * Vec3(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
      for (const Vec3& c : ClosedFormCandidates(s.array, s.array.Tdoa(truth))) {
        const bool exact = (s.array.Tdoa(c) - s.array.Tdoa(truth)).norm() < 1e-9;
        if (exact && (c - truth).norm() > 10.0) {
          s.truth_m = truth;
          s.ghost_m = c;
          return s;
        }
      }
    }
  }
  return s;
}

WeightedBelief Around(const ArrayGeometry& array, const Vec3& p) {
  WeightedBelief b;
  b.belief.mean.head<3>() = p;
  b.belief.covariance.topLeftCorner<3, 3>() = TdoaPositionCrlb(array, p, kSigmaS);
  b.belief.covariance.bottomRightCorner<3, 3>() = Mat3::Identity();  // 1 m/s
  return b;
}

std::unique_ptr<ParticleFilter> MakeFilter(const ArrayGeometry& array, const std::vector<WeightedBelief>& modes) {
  ParticleFilterOptions o;  // the session's defaults: 4096 particles, 1 m/s^2
  o.tdoa_sigma_s = kSigmaS;
  o.seed = 11;
  auto pf = ParticleFilter::Create(array, o);
  EXPECT_TRUE(pf.ok());
  EXPECT_TRUE((*pf)->InitialiseMixture(modes).ok());
  return std::move(*pf);
}

// The hypotheses' moment-matched covariance about the heaviest one's mean (as a session
// reports it), and the truth's squared Mahalanobis distance from that mean under it.
double ReportedNees(const std::vector<WeightedBelief>& hypotheses, const Vec3& truth) {
  const TrackState& best = hypotheses.front().belief;
  Mat3 cov = Mat3::Zero();
  for (const WeightedBelief& h : hypotheses) {
    const Vec3 offset = h.belief.mean.head<3>() - best.mean.head<3>();
    cov += h.weight * (h.belief.covariance.topLeftCorner<3, 3>() + offset * offset.transpose());
  }
  const Vec3 err = best.mean.head<3>() - truth;
  return err.dot(cov.ldlt().solve(err));
}

// Without contenders, resampling by the marginal evidence alone removed the near (true)
// solution here within ~25 frames: white acceleration spreads its predicted TDOAs more than
// the far one's, so every frame favours the far one by a few percent.
TEST(ParticleModes, AnExactSecondSolutionIsHeldAndReportedWhileTheDataCannotSeparateIt) {
  const GhostScene s = FindGhostScene();
  ASSERT_GT((s.ghost_m - s.truth_m).norm(), 10.0) << "no bearing of the list has a second exact solution";
  auto pf = MakeFilter(s.array, {Around(s.array, s.truth_m), Around(s.array, s.ghost_m)});
  std::mt19937_64 rng(5);
  for (int f = 0; f < 60; ++f) {
    if (f > 0) pf->Predict(kHopS);
    ASSERT_TRUE(
        pf->Update(MakeMeasurement(s.array, s.truth_m, Vec3::Zero(), f * kHopS, kSigmaS, kSampleRateHz, rng)).ok());
    const std::vector<WeightedBelief> h = pf->Hypotheses();
    ASSERT_EQ(h.size(), 2u) << "frame " << f;
    EXPECT_GE(h.back().weight, ParticleSet::kContenderShare - 1e-9) << "frame " << f;
    // Whichever solution is reported first, the covariance covers the truth (3-D, 4 sigma).
    EXPECT_LT(ReportedNees(h, s.truth_m), 16.0) << "frame " << f;
    // Both hypotheses still sit on their solutions.
    const bool truth_first = (h.front().belief.mean.head<3>() - s.truth_m).norm() < 3.0;
    const Vec3& other = truth_first ? s.ghost_m : s.truth_m;
    EXPECT_LT((h.back().belief.mean.head<3>() - other).norm(), 5.0) << "frame " << f;
  }
}

// One frame heard at a wrong position (an echo, an impulse: here the TDOAs of a point 8 m
// beside the truth, which a second label holds) sets the truth's label back by far more than
// the contender margin. One update adds at most kContenderStepNats to a label's deficit, so
// the truth stays a contender through that frame, and the frames after, heard at the truth,
// end the wrong label within a few updates instead. (Without the step cap the truth's label
// was dropped on that single frame and the wrong one kept: 8 m off from then on.)
TEST(ParticleModes, OneFrameHeardAtAWrongModeDoesNotEndTheTruth) {
  const GhostScene s = FindGhostScene();
  const Vec3 beside = s.truth_m + 8.0 * s.truth_m.cross(Vec3::UnitZ()).normalized();
  auto pf = MakeFilter(s.array, {Around(s.array, s.truth_m), Around(s.array, beside)});
  std::mt19937_64 rng(7);
  int single_from = -1;
  for (int f = 0; f < 12; ++f) {
    if (f > 0) pf->Predict(kHopS);
    const Vec3& heard = f == 0 ? beside : s.truth_m;
    ASSERT_TRUE(pf->Update(MakeMeasurement(s.array, heard, Vec3::Zero(), f * kHopS, kSigmaS, kSampleRateHz, rng)).ok());
    const std::vector<WeightedBelief> h = pf->Hypotheses();
    if (f == 0) {
      ASSERT_EQ(h.size(), 2u) << "the truth's label ended on one frame";
    } else if (h.size() == 1 && single_from < 0) {
      single_from = f;
    }
  }
  // The step cap holds a label for at least ceil(margin / step) updates of steady evidence.
  EXPECT_GE(single_from, 3);
  EXPECT_LE(single_from, 8);
  const std::vector<WeightedBelief> h = pf->Hypotheses();
  ASSERT_EQ(h.size(), 1u);
  EXPECT_LT((h.front().belief.mean.head<3>() - s.truth_m).norm(), 1.0);
}

// A second mode 8 m beside the truth that no TDOA solution supports: its best particle
// trails the truth's by many nats every frame, so it is no contender and goes.
TEST(ParticleModes, AModeTheDataRuleOutIsDropped) {
  const GhostScene s = FindGhostScene();
  const Vec3 beside = s.truth_m + 8.0 * s.truth_m.cross(Vec3::UnitZ()).normalized();
  auto pf = MakeFilter(s.array, {Around(s.array, s.truth_m), Around(s.array, beside)});
  std::mt19937_64 rng(6);
  for (int f = 0; f < 20; ++f) {
    if (f > 0) pf->Predict(kHopS);
    ASSERT_TRUE(
        pf->Update(MakeMeasurement(s.array, s.truth_m, Vec3::Zero(), f * kHopS, kSigmaS, kSampleRateHz, rng)).ok());
  }
  const std::vector<WeightedBelief> h = pf->Hypotheses();
  ASSERT_EQ(h.size(), 1u);
  EXPECT_LT((h.front().belief.mean.head<3>() - s.truth_m).norm(), 1.0);
}

// A second mode started wide (a far solution parked on the search sphere, its range spread
// tens of metres) whose spread covers the truth: its particles near the truth score as well as
// the truth's own label, so it stays a contender; once it has gathered on the truth the two
// labels are one hypothesis and must be reported as one. Without the merge (ParticleSet::
// MergeCoincidentLabels) this scene reported two hypotheses, 0.9 and 0.1 of the weight at the
// same place, on all 40 frames; acquisition_session_test's four-sensor scene did so for 17 s.
TEST(ParticleModes, ALabelThatGathersOnAnotherBecomesPartOfIt) {
  const GhostScene s = FindGhostScene();
  WeightedBelief wide = Around(s.array, 1.4 * s.truth_m);
  wide.belief.covariance.topLeftCorner<3, 3>() = 15.0 * 15.0 * Mat3::Identity();
  auto pf = MakeFilter(s.array, {Around(s.array, s.truth_m), wide});
  std::mt19937_64 rng(8);
  int single_from = -1;
  for (int f = 0; f < 40; ++f) {
    if (f > 0) pf->Predict(kHopS);
    ASSERT_TRUE(
        pf->Update(MakeMeasurement(s.array, s.truth_m, Vec3::Zero(), f * kHopS, kSigmaS, kSampleRateHz, rng)).ok());
    const std::vector<WeightedBelief> h = pf->Hypotheses();
    if (h.size() == 1 && single_from < 0) single_from = f;
    if (single_from >= 0) {
      EXPECT_EQ(h.size(), 1u) << "frame " << f;
    }
  }
  EXPECT_GE(single_from, 0);
  EXPECT_LE(single_from, 5);
  const std::vector<WeightedBelief> h = pf->Hypotheses();
  ASSERT_EQ(h.size(), 1u);
  EXPECT_LT((h.front().belief.mean.head<3>() - s.truth_m).norm(), 1.0);
  std::printf("the wide label joined the truth's at frame %d\n", single_from);
}

}  // namespace
}  // namespace localizer::engine
