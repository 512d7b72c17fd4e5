// Acquisition::OpenCurve (acquisition.h, "Open curves"): the curve two pairs leave open,
// traced from a point on it and sampled evenly along its length.
#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "engine/acquisition/acquisition.h"

namespace localizer::engine {
namespace {

constexpr int kTraceStepsPerRadius = 16;  // tracing step: radius / 16
constexpr int kMaxCurvePoints = 9;        // points kept along the curve, the start among them
constexpr double kOnCurveLags = 0.25;     // a traced point must meet both lags this closely

}  // namespace

std::vector<CurvePoint> Acquisition::OpenCurve(const Vec3& on_m, const int pair[2], const double lag[2],
                                               const double sigma[2]) const {
  const double fs = field_.sample_rate_hz();
  const int pairs = field_.reference_pairs();
  const Vec3 centre = array_.centroid_m();
  const double radius = search_radius_m();
  // The two pairs' residuals (samples) and gradients (samples per metre) at x.
  auto model = [&](const Vec3& x, Eigen::Vector2d* r, Eigen::Matrix<double, 2, 3>* jac) {
    const Eigen::VectorXd ref_lag = array_.Tdoa(x) * fs;
    const Eigen::MatrixXd ref_jac = array_.TdoaJacobian(x) * fs;
    for (int i = 0; i < 2; ++i) {
      const int q = pair[i];
      (*r)(i) = lag[i] - (q < pairs ? ref_lag(q) : CrossLag(q, ref_lag));
      jac->row(i) = q < pairs ? Eigen::RowVector3d(ref_jac.row(q)) : CrossGradient(q, ref_jac);
    }
  };
  // Onto the curve: minimum-norm Gauss–Newton steps on the two residuals.
  auto settle = [&](Vec3* x) {
    Eigen::Vector2d r;
    Eigen::Matrix<double, 2, 3> jac;
    for (int it = 0; it < 6; ++it) {
      model(*x, &r, &jac);
      if (r.cwiseAbs().maxCoeff() < 1e-6) break;
      const Eigen::Matrix2d jjt = jac * jac.transpose();
      *x += jac.transpose() * jjt.ldlt().solve(r);
    }
    model(*x, &r, &jac);
    return x->allFinite() && r.cwiseAbs().maxCoeff() <= kOnCurveLags;
  };
  auto tangent = [&](const Vec3& x) {
    Eigen::Vector2d r;
    Eigen::Matrix<double, 2, 3> jac;
    model(x, &r, &jac);
    const Vec3 t = Vec3(jac.row(0).transpose()).cross(Vec3(jac.row(1).transpose()));
    return t.norm() > 0.0 ? Vec3(t / t.norm()) : Vec3::Zero();
  };
  // Search keeps a solution out to 1.5 radii before parking it on the sphere: so does the curve.
  auto inside = [&](const Vec3& x) { return (x - centre).norm() <= 1.5 * radius && InBounds(x); };

  Vec3 start = on_m;
  if (!settle(&start) || !inside(start) || tangent(start).isZero()) return {};
  // Trace both ways; `path` runs from one end to the other through the start.
  const double step_m = radius / kTraceStepsPerRadius;
  const int max_steps = 3 * kTraceStepsPerRadius;  // the diameter
  std::vector<Vec3> side[2];
  for (int way = 0; way < 2; ++way) {
    Vec3 x = start, heading = (way == 0 ? 1.0 : -1.0) * tangent(start);
    for (int k = 0; k < max_steps; ++k) {
      Vec3 t = tangent(x);
      if (t.isZero()) break;
      if (t.dot(heading) < 0.0) t = -t;
      Vec3 next = x + step_m * t;
      if (!settle(&next) || !inside(next) || (next - x).norm() < 0.25 * step_m) break;
      side[way].push_back(next);
      heading = t;
      x = next;
    }
  }
  std::vector<Vec3> path(side[1].rbegin(), side[1].rend());
  const size_t start_index = path.size();
  path.push_back(start);
  path.insert(path.end(), side[0].begin(), side[0].end());
  if (path.size() < 2) return {};
  std::vector<double> arc(path.size(), 0.0);
  for (size_t i = 1; i < path.size(); ++i) arc[i] = arc[i - 1] + (path[i] - path[i - 1]).norm();
  // kMaxCurvePoints evenly by length, the one nearest the start replaced by the start.
  const int n = static_cast<int>(std::min<size_t>(kMaxCurvePoints, path.size()));
  const double spacing_m = n > 1 ? arc.back() / (n - 1) : step_m;
  std::vector<size_t> chosen;
  for (int k = 0; k < n; ++k) {
    const double want = k * spacing_m;
    const size_t i = static_cast<size_t>(std::lower_bound(arc.begin(), arc.end(), want - 1e-12) - arc.begin());
    chosen.push_back(std::min(i, path.size() - 1));
  }
  size_t nearest = 0;
  for (size_t k = 1; k < chosen.size(); ++k) {
    if (std::abs(arc[chosen[k]] - arc[start_index]) < std::abs(arc[chosen[nearest]] - arc[start_index])) nearest = k;
  }
  chosen[nearest] = start_index;
  std::sort(chosen.begin(), chosen.end());
  chosen.erase(std::unique(chosen.begin(), chosen.end()), chosen.end());

  std::vector<CurvePoint> out;
  const double along_sd_m = 0.5 * spacing_m;
  for (size_t i : chosen) {
    Eigen::Vector2d r;
    Eigen::Matrix<double, 2, 3> jac;
    model(path[i], &r, &jac);
    Mat3 info = Mat3::Zero();
    for (int k = 0; k < 2; ++k) info += jac.row(k).transpose() * jac.row(k) / (sigma[k] * sigma[k]);
    const Vec3 t = tangent(path[i]);
    info += t * t.transpose() / (along_sd_m * along_sd_m);
    Mat3 cov = info.inverse();
    // The curve bends away from its tangent within the point's reach (half a spacing each
    // way): across the tangent the spread covers how far it bends.
    double bend_m = 0.0;
    for (size_t j = 0; j < path.size(); ++j) {
      if (std::abs(arc[j] - arc[i]) > along_sd_m) continue;
      const Vec3 d = path[j] - path[i];
      bend_m = std::max(bend_m, (d - d.dot(t) * t).norm());
    }
    cov += bend_m * bend_m * (Mat3::Identity() - t * t.transpose());
    if (!cov.allFinite()) continue;
    out.push_back({path[i], 0.5 * (cov + cov.transpose())});
  }
  return out;
}

}  // namespace localizer::engine
