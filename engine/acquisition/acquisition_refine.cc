// Acquisition::Refine (acquisition.h): one cell's picks, the weighted Gauss–Newton solve,
// the consensus subset and the re-pick at the solution.
#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

#include "engine/acquisition/acquisition.h"

namespace localizer::engine {
namespace {

constexpr double kMinPickValue = 3.0;  // a pick below this normalised height is noise
// A pick at least this high stands clear of noise in any window the search picks from
// (acquisition.h, "Open curves").
constexpr double kSurePickValue = 4.5;
constexpr double kMinSigmaSamples = 0.1;  // ~ the sub-sample interpolation's bias (DESIGN.md)
constexpr double kMinFrontEndSigmaSamples = 0.02;
constexpr double kMaxSigmaSamples = 5.0;
// The solve stays within this many search radii of the array's centre. Far out, every pair's
// lag tends to its plane-wave limit, and least squares over redundant pairs (the cross pairs)
// can slide out to millions of metres, where the range direction carries no information at
// all (a 6-hydrophone array's solve, 5e7 m out, had an information matrix of rank 2 to the
// last bit). Search parks a solution beyond 1.5 radii on the sphere anyway.
constexpr double kMaxReachRadii = 3.0;

}  // namespace

bool Acquisition::Refine(const Vec3& start_m, const std::vector<double>& lo, const std::vector<double>& hi,
                         PositionMode* mode) const {
  const int pairs = field_.reference_pairs();
  // Cross pairs with a window are picked and solved too: pair q >= pairs models lag_b - lag_a.
  const int solved = std::min(field_.pair_count(), static_cast<int>(std::min(lo.size(), hi.size())));
  const double fs = field_.sample_rate_hz();
  std::vector<double> pick(static_cast<size_t>(solved), 0.0), sigma(static_cast<size_t>(solved), 1.0);
  std::vector<char> used(static_cast<size_t>(solved), 0);
  std::vector<double> height(static_cast<size_t>(solved), 0.0);
  // Pair p's pick in [a, b]: its lag, and a curvature-based sigma; false when too weak.
  auto pick_in = [&](int p, double a, double b) {
    double lag = 0.0, value = 0.0;
    if (!field_.ArgMax(p, a, b, &lag, &value) || value < kMinPickValue) return false;
    const double left = field_.At(p, std::round(lag) - 1.0), mid = field_.At(p, std::round(lag));
    const double right = field_.At(p, std::round(lag) + 1.0);
    const double curvature = -(left - 2.0 * mid + right);  // -g'' in normalised units per sample^2
    const double s = curvature > 0.0 && mid > 0.0 ? 1.0 / std::sqrt(curvature * mid) : kMaxSigmaSamples;
    pick[static_cast<size_t>(p)] = lag;
    height[static_cast<size_t>(p)] = value;
    sigma[static_cast<size_t>(p)] = std::clamp(s, kMinSigmaSamples, kMaxSigmaSamples);
    // The main peak: the front end's own delay and sigma (from the whole cross-spectrum,
    // gcc_phat.h) are better than a parabola through three samples.
    if (measurement_ != nullptr && p < pairs) {
      const PairMeasurement& pm = measurement_->pairs[static_cast<size_t>(p)];
      if (pm.delay_sigma_s > 0.0 && std::abs(pm.delay_s * fs - lag) < 0.5) {
        pick[static_cast<size_t>(p)] = pm.delay_s * fs;
        sigma[static_cast<size_t>(p)] = std::clamp(pm.delay_sigma_s * fs, kMinFrontEndSigmaSamples, kMaxSigmaSamples);
      }
    }
    return true;
  };
  // Every solved pair's lag (samples) and its gradient (samples per metre) at x.
  auto model = [&](const Vec3& x, Eigen::VectorXd* lag, Eigen::MatrixXd* jac) {
    const Eigen::VectorXd ref_lag = array_.Tdoa(x) * fs;
    lag->resize(solved);
    lag->head(pairs) = ref_lag;
    for (int q = pairs; q < solved; ++q) (*lag)(q) = CrossLag(q, ref_lag);
    if (jac == nullptr) return;
    const Eigen::MatrixXd ref_jac = array_.TdoaJacobian(x) * fs;
    jac->resize(solved, 3);
    jac->topRows(pairs) = ref_jac;
    for (int q = pairs; q < solved; ++q) jac->row(q) = CrossGradient(q, ref_jac);
  };
  int count = 0;
  for (int p = 0; p < solved; ++p) {
    used[static_cast<size_t>(p)] = pick_in(p, lo[static_cast<size_t>(p)], hi[static_cast<size_t>(p)]);
    count += used[static_cast<size_t>(p)];
  }
  if (count < 3) return false;

  const Vec3 centre = array_.centroid_m();
  const double max_reach_m = kMaxReachRadii * search_radius_m();
  // And within the bounds (a projected Gauss–Newton): with every pair in the fit, a source at
  // a bound (a fish by the seabed) can solve a few decimetres beyond it, and a solution
  // outside is no mode at all (XAV: three call frames with none).
  const auto within_reach = [&](const Vec3& p) -> Vec3 {
    const double reach_m = (p - centre).norm();
    const Vec3 q = reach_m > max_reach_m ? Vec3(centre + max_reach_m / reach_m * (p - centre)) : p;
    return q.cwiseMax(options_.bounds_min_m).cwiseMin(options_.bounds_max_m);
  };
  Vec3 x = within_reach(start_m);
  Mat3 info = Mat3::Zero();
  // Weighted Gauss–Newton with Levenberg damping on the used pairs; returns the final cost.
  auto solve = [&]() {
    double lambda = 1e-3;
    double cost = 0.0;
    for (int it = 0; it < 30; ++it) {
      Eigen::VectorXd lag;
      Eigen::MatrixXd jac;  // samples per metre
      model(x, &lag, &jac);
      Mat3 a = Mat3::Zero();
      Vec3 g = Vec3::Zero();
      cost = 0.0;
      for (int p = 0; p < solved; ++p) {
        if (!used[static_cast<size_t>(p)]) continue;
        const double w = 1.0 / (sigma[static_cast<size_t>(p)] * sigma[static_cast<size_t>(p)]);
        const Eigen::Vector3d row = jac.row(p).transpose();
        const double r = pick[static_cast<size_t>(p)] - lag(p);
        a += w * row * row.transpose();
        g += w * row * r;
        cost += w * r * r;
      }
      info = a;
      bool stepped = false;
      for (int tries = 0; tries < 8 && !stepped; ++tries) {
        Mat3 damped = a;
        damped.diagonal() += lambda * (a.diagonal().array() + 1e-12).matrix();
        const Vec3 step = damped.ldlt().solve(g);
        if (!step.allFinite()) break;
        const Vec3 candidate = within_reach(x + step);
        Eigen::VectorXd lag2;
        model(candidate, &lag2, nullptr);
        double cost2 = 0.0;
        for (int p = 0; p < solved; ++p) {
          if (!used[static_cast<size_t>(p)]) continue;
          const double r = pick[static_cast<size_t>(p)] - lag2(p);
          cost2 += r * r / (sigma[static_cast<size_t>(p)] * sigma[static_cast<size_t>(p)]);
        }
        if (cost2 <= cost) {
          stepped = true;
          const double moved = step.norm();
          x = candidate;
          lambda = std::max(lambda * 0.3, 1e-9);
          if (moved < 1e-7 * std::max(1.0, x.norm())) return cost2;
        } else {
          lambda *= 10.0;
        }
      }
      if (!stepped) break;
    }
    return cost;
  };
  double cost = solve();
  // Consensus: leave out the worst pair while it is off the solution (keep >= 3).
  while (count > 3) {
    Eigen::VectorXd lag;
    model(x, &lag, nullptr);
    int worst = -1;
    double worst_excess = 0.0;
    for (int p = 0; p < solved; ++p) {
      if (!used[static_cast<size_t>(p)]) continue;
      const double r = std::abs(pick[static_cast<size_t>(p)] - lag(p));
      const double allowed = std::max(3.0 * sigma[static_cast<size_t>(p)], 1.5);
      if (r > allowed && r / allowed > worst_excess) {
        worst_excess = r / allowed;
        worst = p;
      }
    }
    if (worst < 0) break;
    used[static_cast<size_t>(worst)] = 0;
    --count;
    solve();
  }
  // Re-pick every pair near the solution's lags (a pair may now find its true peak), solve again.
  {
    Eigen::VectorXd lag;
    model(x, &lag, nullptr);
    count = 0;
    for (int p = 0; p < solved; ++p) {
      used[static_cast<size_t>(p)] = pick_in(p, lag(p) - 2.0, lag(p) + 2.0);
      count += used[static_cast<size_t>(p)];
    }
    if (count < 3) return false;
    cost = solve();
  }
  if (!x.allFinite()) return false;
  Eigen::LDLT<Mat3> ldlt(info);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0)) return false;
  // With redundant pairs, the fit's own residual scales the covariance up when the peaks
  // are less precise than their curvature says (multipath biases them): the a-posteriori
  // variance factor of least squares, never below 1.
  const double variance_factor = count > 3 ? std::max(1.0, cost / (count - 3)) : 1.0;
  const Mat3 cov = variance_factor * ldlt.solve(Mat3::Identity());
  if (!cov.allFinite()) return false;
  mode->position_m = x;
  mode->covariance_m2 = 0.5 * (cov + cov.transpose());
  mode->pairs_used = count;
  mode->score = Score(x);
  // Only two picks clear of noise: the curve they leave open (acquisition.h, "Open curves").
  int sure[2] = {-1, -1}, sure_count = 0;
  for (int p = 0; p < solved; ++p) {
    if (!used[static_cast<size_t>(p)] || height[static_cast<size_t>(p)] < kSurePickValue) continue;
    if (sure_count < 2) sure[sure_count] = p;
    ++sure_count;
  }
  mode->open_curve.clear();
  if (sure_count == 2) {
    const double lag[2] = {pick[static_cast<size_t>(sure[0])], pick[static_cast<size_t>(sure[1])]};
    const double sd[2] = {sigma[static_cast<size_t>(sure[0])], sigma[static_cast<size_t>(sure[1])]};
    mode->open_curve = OpenCurve(x, sure, lag, sd);
  }
  return true;
}

}  // namespace localizer::engine
