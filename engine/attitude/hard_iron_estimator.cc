#include "engine/attitude/hard_iron_estimator.h"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <cmath>

namespace localizer::engine {
namespace {

// Fewer (weighted) samples than this and the fit says nothing: a fraction of a second.
constexpr double kMinWeight = 50.0;
// The attitude error the misfit allows for on top of the field's tolerance: an attitude off
// by e rad misplaces R b by e |b|, so a large offset fits less well for the same attitude.
constexpr double kAttitudeSdRad = 0.01;

}  // namespace

HardIronFit HardIronEstimator::Solve(const Eigen::Matrix3d& body_to_world) const {
  HardIronFit fit;
  const double s0 = sums_.s0;
  if (s0 < kMinWeight) return fit;
  const Eigen::Matrix3d m = sums_.sr / s0;
  const Eigen::Vector3d mean_y = sums_.Sy() / s0;
  const Eigen::Vector3d mean_m = sums_.sm / s0;
  const Eigen::Matrix3d a = Eigen::Matrix3d::Identity() - m.transpose() * m;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
  eigen.computeDirect(a, Eigen::EigenvaluesOnly);
  fit.diversity = std::max(0.0, eigen.eigenvalues()(0));  // ascending order
  if (fit.diversity < 1e-6) return fit;                   // A singular: no offset to solve for
  const Eigen::Matrix3d a_inv = a.inverse();
  fit.offset_uT = a_inv * (mean_m - m.transpose() * mean_y);
  fit.field_world_uT = mean_y - m * fit.offset_uT;
  const double misfit = sums_.smm.trace() / s0 - fit.field_world_uT.dot(mean_y) - fit.offset_uT.dot(mean_m);
  fit.residual_uT = std::sqrt(std::max(0.0, misfit));
  // The heading-relevant part: the world's horizontal axis across the field's horizontal
  // part, seen in the body at the current attitude.
  const Eigen::Vector3d across(-fit.field_world_uT.y(), fit.field_world_uT.x(), 0.0);
  const double across_norm = across.norm();
  if (across_norm > 0.0) {
    const Eigen::Vector3d u = body_to_world.transpose() * (across / across_norm);
    fit.heading_diversity = 1.0 / std::max(u.dot(a_inv * u), 1.0);
  }
  fit.trusted = fit.diversity >= min_diversity_ && fit.residual_uT <= AllowedResidual(fit);
  return fit;
}

double HardIronEstimator::AllowedResidual(const HardIronFit& fit) const {
  return max_residual_ * fit.field_world_uT.norm() + kAttitudeSdRad * fit.offset_uT.norm();
}

double HardIronEstimator::ResidualWith(const Eigen::Vector3d& offset_uT) const {
  if (sums_.s0 <= 0.0) return 0.0;
  const Eigen::Vector3d world = FieldWith(offset_uT);
  const double misfit =
      (sums_.smm.trace() - 2.0 * offset_uT.dot(sums_.sm)) / sums_.s0 + offset_uT.squaredNorm() - world.squaredNorm();
  return std::sqrt(std::max(0.0, misfit));
}

}  // namespace localizer::engine
