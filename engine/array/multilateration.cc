#include "engine/array/multilateration.h"

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace localizer::engine {
namespace {

double Cost(const ArrayGeometry& array, const Vec3& s, const Eigen::VectorXd& d, double sigma) {
  return ((array.Tdoa(s) - d) / sigma).squaredNorm();
}

// Levenberg–Marquardt with Marquardt's diagonal scaling; returns the refined fix.
Fix Refine(const ArrayGeometry& array, Vec3 s, const Eigen::VectorXd& d, const MultilaterationOptions& options) {
  const double sigma = options.tdoa_sigma_s;
  double lambda = 1e-3;
  double cost = Cost(array, s, d, sigma);
  Fix fix;
  for (int it = 0; it < options.max_iterations; ++it) {
    fix.iterations = it + 1;
    const Eigen::MatrixXd jac = array.TdoaJacobian(s) / sigma;
    const Eigen::VectorXd res = (array.Tdoa(s) - d) / sigma;
    const Mat3 jtj = jac.transpose() * jac;
    const Vec3 grad = jac.transpose() * res;
    bool improved = false;
    for (int tries = 0; tries < 10 && !improved; ++tries) {
      Mat3 damped = jtj;
      damped.diagonal() += lambda * jtj.diagonal().cwiseMax(1e-12);
      const Vec3 step = -damped.ldlt().solve(grad);
      const Vec3 candidate = s + step;
      const double candidate_cost = Cost(array, candidate, d, sigma);
      if (std::isfinite(candidate_cost) && candidate_cost <= cost) {
        improved = true;
        const bool small = step.norm() < 1e-9 * (1.0 + s.norm()) || cost - candidate_cost < 1e-12 * (1.0 + cost);
        s = candidate;
        cost = candidate_cost;
        lambda = std::max(lambda * 0.3, 1e-12);
        if (small) fix.converged = true;
      } else {
        lambda *= 10.0;
      }
    }
    if (!improved) fix.converged = true;  // no downhill step left: at a minimum
    if (fix.converged) break;
  }
  fix.position_m = s;
  fix.rms_residual_s = std::sqrt(cost / static_cast<double>(d.size())) * sigma;
  fix.covariance_m2 = TdoaPositionCrlb(array, s, sigma);
  return fix;
}

}  // namespace

std::vector<Vec3> ClosedFormCandidates(const ArrayGeometry& array, const Eigen::VectorXd& tdoa_s) {
  const Eigen::VectorXd& d = tdoa_s;
  const int pairs = array.pair_count();
  const Vec3& ref = array.sensor_m(array.reference_sensor());
  Eigen::MatrixXd ax(pairs, 3);
  Eigen::VectorXd delta(pairs), rhs(pairs);
  for (int p = 0; p < pairs; ++p) {
    const Vec3 x = array.sensor_m(array.sensor_of_pair(p)) - ref;
    delta(p) = array.sound_speed_mps() * d(p);
    ax.row(p) = x.transpose();
    rhs(p) = 0.5 * (x.squaredNorm() - delta(p) * delta(p));
  }
  const auto qr = ax.colPivHouseholderQr();
  const Vec3 a = qr.solve(rhs);
  const Vec3 b = qr.solve(-delta);
  // (|b|^2 - 1) r^2 + 2 a.b r + |a|^2 = 0
  const double qa = b.squaredNorm() - 1.0, qb = 2.0 * a.dot(b), qc = a.squaredNorm();
  std::vector<double> ranges;
  if (std::abs(qa) < 1e-12) {
    if (std::abs(qb) > 1e-12) ranges.push_back(-qc / qb);
  } else {
    const double disc = qb * qb - 4.0 * qa * qc;
    if (disc >= 0.0) {
      const double root = std::sqrt(disc);
      ranges.push_back((-qb + root) / (2.0 * qa));
      ranges.push_back((-qb - root) / (2.0 * qa));
    } else {
      ranges.push_back(-qb / (2.0 * qa));  // noise pushed the roots apart: take the vertex
    }
  }
  std::vector<Vec3> candidates;
  for (double r : ranges) {
    if (r >= 0.0 && std::isfinite(r)) candidates.push_back(ref + a + b * r);
  }
  // Always also start from the array centre pushed along the first-order direction, so a
  // fix exists even when the quadratic gives nothing usable.
  candidates.push_back(array.centroid_m() + a.normalized() * array.aperture_m());
  return candidates;
}

Mat3 TdoaPositionCrlb(const ArrayGeometry& array, const Vec3& source_m, double tdoa_sigma_s) {
  const Eigen::MatrixXd h = array.TdoaJacobian(source_m);
  const Mat3 info = h.transpose() * h;
  return tdoa_sigma_s * tdoa_sigma_s * info.completeOrthogonalDecomposition().pseudoInverse();
}

Mat3 TdoaPositionCrlb(const ArrayGeometry& array, const Vec3& source_m, const Eigen::VectorXd& sigma_s) {
  const Eigen::MatrixXd h = array.TdoaJacobian(source_m);
  const Eigen::MatrixXd whitened = sigma_s.cwiseInverse().asDiagonal() * h;
  const Mat3 info = whitened.transpose() * whitened;
  return info.completeOrthogonalDecomposition().pseudoInverse();
}

StatusOr<Fix> Multilaterate(const ArrayGeometry& array, const Eigen::VectorXd& tdoa_s,
                            const MultilaterationOptions& options) {
  if (tdoa_s.size() != array.pair_count()) {
    return InvalidArgument("multilateration got " + std::to_string(tdoa_s.size()) + " TDOAs; the array has " +
                           std::to_string(array.pair_count()) + " pairs");
  }
  if (!tdoa_s.allFinite()) return InvalidArgument("multilateration got a non-finite TDOA");
  if (!(options.tdoa_sigma_s > 0.0)) {
    return InvalidArgument("tdoa_sigma_s must be positive, got " + std::to_string(options.tdoa_sigma_s));
  }
  const Vec3 centre = array.centroid_m();
  bool have = false;
  Fix best;
  double best_cost = std::numeric_limits<double>::infinity();
  for (const Vec3& start : ClosedFormCandidates(array, tdoa_s)) {
    const Fix fix = Refine(array, start, tdoa_s, options);
    if (!fix.position_m.allFinite()) continue;
    const double cost = Cost(array, fix.position_m, tdoa_s, options.tdoa_sigma_s);
    bool better = cost < best_cost - 1e-9;
    if (!better && std::abs(cost - best_cost) <= 1e-9 && have) {
      const Vec3 anchor = options.hint_m ? *options.hint_m : centre;
      better = (fix.position_m - anchor).norm() < (best.position_m - anchor).norm();
    }
    if (!have || better) {
      best = fix;
      best_cost = cost;
      have = true;
    }
  }
  if (!have) return FailedPrecondition("multilateration found no finite position for these TDOAs");
  return best;
}

}  // namespace localizer::engine
