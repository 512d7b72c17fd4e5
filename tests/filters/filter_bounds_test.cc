// Each filter's accuracy as a ratio to the posterior CRLB (engine/filters/posterior_crlb.h)
// for its own motion model along the true path, and its consistency (NEES per dimension),
// on constant-velocity, constant-acceleration and turning targets (bound_scenes.h).
// Every filter runs with its defaults and the true TDOA noise; 4 seeds per case, pooled.
// On the deterministic paths the bound (which assumes random accelerations of 1 m/s^2)
// can be beaten and the filters are somewhat conservative (NEES per dimension ~0.5-0.7);
// on cv-random the truth is a draw from the CV model and both should be near 1.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cstdio>
#include <functional>
#include <memory>

#include "engine/filters/imm_filter.h"
#include "engine/filters/kalman_filter.h"
#include "engine/filters/multi_model_pf.h"
#include "engine/filters/particle_filter.h"
#include "tests/filters/bound_scenes.h"

namespace localizer::engine {
namespace {

using testing::BoundScene;

constexpr double kStartPosStdM = 0.1;
constexpr double kStartVelStdMps = 0.2;
constexpr double kSkipS = 1.0;  // the start transient is not scored

struct FilterCase {
  std::string name;   // as printed
  std::string model;  // the motion model the bound assumes
  std::function<std::unique_ptr<Tracker>(const ArrayGeometry&, uint64_t seed)> make;
  double extra_std = 1.0;  // the filter's prior std of the model's extra entries
};

struct CaseResult {
  double rmse_m = 0.0;
  double bound_m = 0.0;  // RMS over scored steps of sqrt(trace(position block of the PCRLB))
  double nees_per_dim = 0.0;
  double ratio() const { return rmse_m / bound_m; }
};

KalmanOptions Kalman(KalmanVariant variant, const std::string& model, double sigma_s) {
  KalmanOptions o;
  o.variant = variant;
  o.motion_model = *ParseMotionModelKind(model, "motion_model");
  o.tdoa_sigma_s = sigma_s;
  return o;
}

std::vector<FilterCase> Filters(double sigma_s) {
  std::vector<FilterCase> cases;
  cases.push_back({"pf", "cv", [sigma_s](const ArrayGeometry& a, uint64_t seed) {
                     ParticleFilterOptions o;
                     o.tdoa_sigma_s = sigma_s;
                     o.seed = seed;
                     return std::unique_ptr<Tracker>(std::move(*ParticleFilter::Create(a, o)));
                   }});
  for (const auto& [variant, vname] :
       {std::pair{KalmanVariant::kExtended, "ekf"}, {KalmanVariant::kUnscented, "ukf"}}) {
    for (const char* model : {"cv", "ca", "ct"}) {
      // Copied: clang 14 cannot capture a structured binding (C++20 allows it; GCC does).
      cases.push_back({std::string(vname) + "-" + model, model,
                       [kalman_variant = variant, model, sigma_s](const ArrayGeometry& a, uint64_t) {
                         return std::unique_ptr<Tracker>(
                             std::move(*KalmanFilter::Create(a, Kalman(kalman_variant, model, sigma_s))));
                       }});
    }
  }
  // The multiple-model filters against the CV model's bound (their first mode).
  cases.push_back({"mmpf", "cv", [sigma_s](const ArrayGeometry& a, uint64_t seed) {
                     MultiModelPfOptions o;
                     o.particle.tdoa_sigma_s = sigma_s;
                     o.particle.seed = seed;
                     return std::unique_ptr<Tracker>(std::move(*MultiModelParticleFilter::Create(a, o)));
                   }});
  cases.push_back({"imm", "cv", [sigma_s](const ArrayGeometry& a, uint64_t) {
                     ImmOptions o;
                     o.kalman.tdoa_sigma_s = sigma_s;
                     return std::unique_ptr<Tracker>(std::move(*ImmFilter::Create(a, o)));
                   }});
  return cases;
}

// The PCRLB of `c`'s motion model (default options) along the scene's path, from the
// filters' start belief.
std::vector<Eigen::MatrixXd> Bound(const ArrayGeometry& array, const BoundScene& scene,
                                   const std::vector<testing::PathPoint>& path, const FilterCase& c) {
  auto model = MakeMotionModel(*ParseMotionModelKind(c.model, "motion_model"), MotionModelOptions{});
  EXPECT_TRUE(model.ok());
  std::vector<TrueState> truth;
  for (int k = 0; k <= scene.steps(); ++k) {
    truth.push_back({k * scene.dt_s, testing::TrueStateFor(c.model, path[k])});
  }
  const int n = (*model)->state_dim();
  Eigen::VectorXd prior_var = Eigen::VectorXd::Constant(n, c.extra_std * c.extra_std);
  prior_var.head<3>().setConstant(kStartPosStdM * kStartPosStdM);
  prior_var.segment<3>(3).setConstant(kStartVelStdMps * kStartVelStdMps);
  const Eigen::MatrixXd j0 = prior_var.cwiseInverse().asDiagonal();
  auto bound = PosteriorCrlb(array, **model, truth, Eigen::VectorXd::Constant(array.pair_count(), scene.sigma_s), j0);
  EXPECT_TRUE(bound.ok()) << bound.status().ToString();
  return bound.ok() ? *bound : std::vector<Eigen::MatrixXd>{};
}

CaseResult RunCase(const ArrayGeometry& array, const BoundScene& scene, const FilterCase& c, int seeds) {
  double se = 0.0, bound2 = 0.0, nees = 0.0;
  int n = 0;
  for (int seed = 1; seed <= seeds; ++seed) {
    const std::vector<testing::PathPoint> path = testing::MakePath(scene, 500 + seed);
    const std::vector<Eigen::MatrixXd> bound = Bound(array, scene, path, c);
    std::mt19937_64 rng(1000 + seed);
    std::normal_distribution<double> noise(0.0, scene.sigma_s);
    auto tracker = c.make(array, seed);
    EXPECT_TRUE(tracker->Initialise(testing::StartOf(path[0], kStartPosStdM, kStartVelStdMps)).ok());
    for (int k = 1; k <= scene.steps(); ++k) {
      const double t = k * scene.dt_s;
      const testing::PathPoint& truth = path[k];
      tracker->Predict(scene.dt_s);
      EXPECT_TRUE(tracker->Update(testing::TdoaFrame(array, truth.position_m, truth.velocity_mps, t, noise, rng)).ok());
      if (t < kSkipS) continue;
      const TrackState s = tracker->State();
      Vec6 e;
      e << s.mean.head<3>() - truth.position_m, s.mean.tail<3>() - truth.velocity_mps;
      se += e.head<3>().squaredNorm();
      bound2 += bound[k].topLeftCorner<3, 3>().trace();
      nees += e.dot(s.covariance.ldlt().solve(e)) / 6.0;
      ++n;
    }
  }
  return {std::sqrt(se / n), std::sqrt(bound2 / n), nees / n};
}

TEST(FilterBounds, EveryFilterWithinAStatedMultipleOfThePosteriorCrlb) {
  const ArrayGeometry array = testing::BoxArray();
  std::printf("%-8s %-9s %10s %10s %8s %8s\n", "filter", "target", "rmse_m", "pcrlb_m", "ratio", "nees/dim");
  for (const char* path : {"cv", "ca", "turn", "cv-random"}) {
    BoundScene scene;
    scene.path = path;
    for (const FilterCase& c : Filters(scene.sigma_s)) {
      const CaseResult r = RunCase(array, scene, c, 4);
      std::printf("%-8s %-9s %10.4f %10.4f %8.2f %8.2f\n", c.name.c_str(), path, r.rmse_m, r.bound_m, r.ratio(),
                  r.nees_per_dim);
      SCOPED_TRACE(c.name + " on " + path);
      // The stated multiple: within 1.5x of the bound for its own model on every target
      // (measured 0.83-1.21), and never overconfident beyond 2x.
      EXPECT_LT(r.ratio(), 1.5);
      EXPECT_LT(r.nees_per_dim, 2.0);
      if (std::string(path) == "cv-random" && c.model != "ca") {
        // The truth is a draw from the model these filters assume: efficient and consistent
        // (the goal: NEES per dimension between 0.5 and 2).
        EXPECT_GT(r.ratio(), 0.8);
        EXPECT_GT(r.nees_per_dim, 0.5);
      }
    }
  }
}

}  // namespace
}  // namespace localizer::engine
