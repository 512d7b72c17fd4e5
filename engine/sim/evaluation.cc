#include "engine/sim/evaluation.h"

#include <algorithm>
#include <cmath>

#include "engine/array/multilateration.h"

namespace localizer::engine {
TrackScore ScoreTrack(const ArrayGeometry& array, const SimResult& truth, const std::vector<Estimate>& estimates,
                      double skip_s) {
  return ScoreTrack([&array](double) { return array; }, truth, estimates, skip_s);
}

TrackScore ScoreTrack(const std::function<ArrayGeometry(double)>& array_at, const SimResult& truth,
                      const std::vector<Estimate>& estimates, double skip_s) {
  TrackScore score;
  const int pairs = array_at(0.0).pair_count();
  const double t_end = truth.truth.empty() ? 0.0 : truth.truth.back().t_s;
  std::vector<const Estimate*> used;
  std::vector<std::vector<double>> tdoa_errors(pairs);
  for (const Estimate& e : estimates) {
    if (e.reinitialised) ++score.reinitialisations;
    if (!e.initialised || e.t_s < skip_s || e.t_s > t_end) continue;
    used.push_back(&e);
    const ArrayGeometry array = array_at(e.t_s);
    for (int p = 0; p < pairs && p < static_cast<int>(e.delay_s.size()); ++p) {
      const Vec3 at = truth.TruthAt(e.t_s - 0.5 * e.delay_s[p]).position_m;
      tdoa_errors[p].push_back(e.delay_s[p] - array.Tdoa(at)(p));
    }
  }
  score.scored = static_cast<int>(used.size());
  if (used.empty()) return score;
  Eigen::VectorXd sigma(pairs);
  for (int p = 0; p < pairs; ++p) {
    const std::vector<double>& err = tdoa_errors[p];
    double ss = 0.0;
    for (double x : err) ss += x * x;
    sigma(p) = std::sqrt(ss / static_cast<double>(err.size()));
    sigma(p) = std::max(sigma(p), 1e-9);
    score.tdoa_sigma_s.push_back(sigma(p));
  }
  std::vector<double> errors;
  double se = 0.0, crlb2 = 0.0;
  for (const Estimate* e : used) {
    const Vec3 at = truth.TruthAt(e->t_s).position_m;
    const double err = (e->state.head<3>() - at).norm();
    errors.push_back(err);
    se += err * err;
    crlb2 += TdoaPositionCrlb(array_at(e->t_s), at, sigma).trace();
  }
  const double n = static_cast<double>(errors.size());
  score.rmse_m = std::sqrt(se / n);
  score.crlb_m = std::sqrt(crlb2 / n);
  score.rmse_over_crlb = score.rmse_m / score.crlb_m;
  std::sort(errors.begin(), errors.end());
  score.median_m = errors[errors.size() / 2];
  score.p95_m = errors[static_cast<size_t>(std::ceil(0.95 * n)) - 1];
  score.max_m = errors.back();
  return score;
}

}  // namespace localizer::engine
