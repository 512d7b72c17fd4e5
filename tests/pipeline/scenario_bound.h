// A session's track against the posterior CRLB and its consistency: shared by
// tests/pipeline and tests/bench/filter_report.cc.
//
// The bound (engine/filters/posterior_crlb.h) is the constant-velocity model's with the
// session's acceleration noise, along the simulator's true path, at the session's frame
// times from its first initialised frame on; the TDOA noise is the measured spread per
// pair (TrackScore::tdoa_sigma_s, as the per-frame CRLB uses); the prior is the first
// frame's TDOA information plus the session's initial velocity spread, as the session
// initialises its filter from the first fix. NEES is over (p, v) with the estimate's own
// covariance, per dimension.
#pragma once

#include <Eigen/Cholesky>
#include <cmath>
#include <vector>

#include "engine/filters/posterior_crlb.h"
#include "engine/pipeline/session.h"
#include "engine/sim/evaluation.h"

namespace localizer::engine {

struct BoundScore {
  double pcrlb_m = 0.0;  // RMS over scored frames of sqrt(trace(position block))
  double rmse_over_pcrlb = 0.0;
  double nees_per_dim = 0.0;  // mean over scored frames of NEES / 6
};

inline BoundScore ScoreAgainstPcrlb(const ArrayGeometry& array, const SimResult& sim, const AudioSessionConfig& config,
                                    const std::vector<Estimate>& estimates, const TrackScore& score, double skip_s) {
  BoundScore out;
  if (score.scored == 0 || static_cast<int>(score.tdoa_sigma_s.size()) != array.pair_count()) return out;
  std::vector<TrueState> truth;
  std::vector<const Estimate*> used;
  for (const Estimate& e : estimates) {
    if (!e.initialised) continue;
    if (e.reinitialised) {  // the filter restarted: so does the bound
      truth.clear();
      used.clear();
    }
    const TruthRow row = sim.TruthAt(e.t_s);
    Eigen::VectorXd x(6);
    x.head<3>() = row.position_m;
    x.tail<3>() = row.velocity_mps;
    truth.push_back({e.t_s, x});
    used.push_back(&e);
  }
  if (truth.empty()) return out;
  const Eigen::VectorXd sigma = Eigen::Map<const Eigen::VectorXd>(score.tdoa_sigma_s.data(), array.pair_count());
  Eigen::MatrixXd j0 = TdoaInformation(array, truth[0].state, sigma);
  j0.bottomRightCorner<3, 3>() += Mat3::Identity() / (config.init_speed_sigma_mps * config.init_speed_sigma_mps);
  MotionModelOptions motion;
  motion.accel_noise_mps2 = config.tracker.particle.accel_noise_mps2;
  auto model = MakeMotionModel(MotionModelKind::kCv, motion);
  if (!model.ok()) return out;
  auto bound = PosteriorCrlb(array, **model, truth, sigma, j0);
  if (!bound.ok()) return out;
  const double t_end = sim.truth.empty() ? 0.0 : sim.truth.back().t_s;
  double se = 0.0, b2 = 0.0, nees = 0.0;
  int n = 0;
  for (size_t k = 0; k < used.size(); ++k) {
    const Estimate& e = *used[k];
    if (e.t_s < skip_s || e.t_s > t_end) continue;
    Vec6 err = e.state - truth[k].state;
    se += err.head<3>().squaredNorm();
    b2 += (*bound)[k].topLeftCorner<3, 3>().trace();
    nees += err.dot(e.covariance.ldlt().solve(err)) / 6.0;
    ++n;
  }
  if (n == 0) return out;
  out.pcrlb_m = std::sqrt(b2 / n);
  out.rmse_over_pcrlb = std::sqrt(se / n) / out.pcrlb_m;
  out.nees_per_dim = nees / n;
  return out;
}

}  // namespace localizer::engine
