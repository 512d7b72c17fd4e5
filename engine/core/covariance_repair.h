// A covariance that rounding left indefinite, made positive definite for a client to use.
//
// Why: the particle filter's moments are float sums, so a cloud tens of metres long in one
// direction (a far-field start) knows its thin directions only to about 1e-7 of its longest
// variance, and an estimate's covariance came out with a negative eigenvalue (campaign scene
// 19000190's first frame: -1.4e-5 m^2 beside 324 m^2): a client's Cholesky or Mahalanobis
// distance then fails. How: when the Cholesky factorisation fails, the correlation matrix
// (each variance scaled to 1, so positions and velocities weigh alike whatever their units)
// has its eigenvalues raised to at least kCorrelationFloor and the covariance is rebuilt
// with the same variances' scale; a variance that is not positive is first set to
// kCorrelationFloor times the largest. A matrix whose Cholesky succeeds is returned as it is,
// bit for bit. Cost: one Cholesky (and, rarely, one symmetric eigen-decomposition).
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>

namespace localizer::engine {

inline constexpr double kCorrelationFloor = 1e-6;

template <int N>
Eigen::Matrix<double, N, N> PositiveDefinite(const Eigen::Matrix<double, N, N>& covariance) {
  using Matrix = Eigen::Matrix<double, N, N>;
  using Vector = Eigen::Matrix<double, N, 1>;
  if (!covariance.allFinite() || Eigen::LLT<Matrix>(covariance).info() == Eigen::Success) return covariance;
  const Matrix symmetric = 0.5 * (covariance + covariance.transpose());
  const double largest = std::max(symmetric.diagonal().maxCoeff(), 0.0);
  const double least = largest > 0.0 ? kCorrelationFloor * largest : 1.0;
  const Vector scale = symmetric.diagonal().cwiseMax(least).cwiseSqrt();
  const Matrix correlation = scale.cwiseInverse().asDiagonal() * symmetric * scale.cwiseInverse().asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Matrix> eig(correlation);
  const Matrix repaired =
      eig.eigenvectors() * eig.eigenvalues().cwiseMax(kCorrelationFloor).asDiagonal() * eig.eigenvectors().transpose();
  return scale.asDiagonal() * repaired * scale.asDiagonal();
}

}  // namespace localizer::engine
