#include "engine/attitude/soft_iron_estimator.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace localizer::engine {
namespace {

using Matrix12d = Eigen::Matrix<double, 12, 12>;
using Matrix11d = Eigen::Matrix<double, 11, 11>;
using Vector11d = Eigen::Matrix<double, 11, 1>;
using Vector12d = Eigen::Matrix<double, 12, 1>;

// As the hard-iron fit: fewer (weighted) samples than this and the fit says nothing, and the
// attitude error the misfit allows for, per µT of offset.
constexpr double kMinWeight = 50.0;
constexpr double kAttitudeSdRad = 0.01;

// A m = sum_i m_i B_i a for a = (A11, A22, A33, A12, A13, A23): B_i (3x6) picks the entries of
// A that multiply m_i, row by row.
Eigen::Matrix<double, 3, 6> Selector(int i) {
  static constexpr int kColumn[3][3] = {{0, 3, 4}, {3, 1, 5}, {4, 5, 2}};  // A(row, i) -> a index
  Eigen::Matrix<double, 3, 6> b = Eigen::Matrix<double, 3, 6>::Zero();
  for (int row = 0; row < 3; ++row) b(row, kColumn[row][i]) = 1.0;
  return b;
}

// The normal matrix N of e = A m - c - R^T m_w over theta = (a, c, m_w): sum w J^T J with
// J = [M(m), -I, -R^T], M(m) = sum_i m_i B_i.
Matrix12d NormalMatrix(const MagCalibrationSums& s) {
  Eigen::Matrix<double, 3, 6> b[3] = {Selector(0), Selector(1), Selector(2)};
  Matrix12d n = Matrix12d::Zero();
  Eigen::Matrix<double, 6, 6> aa = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 3> ac = Eigen::Matrix<double, 6, 3>::Zero();
  Eigen::Matrix<double, 6, 3> aw = Eigen::Matrix<double, 6, 3>::Zero();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) aa += s.smm(i, j) * b[i].transpose() * b[j];
    ac -= s.sm(i) * b[i].transpose();
    aw -= b[i].transpose() * s.smr[i].transpose();  // sum w M^T R^T
  }
  n.topLeftCorner<6, 6>() = aa;
  n.block<6, 3>(0, 6) = ac;
  n.block<6, 3>(0, 9) = aw;
  n.block<3, 3>(6, 6).diagonal().setConstant(s.s0);
  n.block<3, 3>(6, 9) = s.sr.transpose();  // (-I)^T (-R^T)
  n.block<3, 3>(9, 9).diagonal().setConstant(s.s0);
  return n.selfadjointView<Eigen::Upper>();
}

// The traceless symmetric matrices in a-coordinates, orthonormal in the Frobenius norm
// (off-diagonal entries count twice): diag(1,-1,0)/√2, diag(1,1,-2)/√6, (E_ij + E_ji)/√2.
Eigen::Matrix<double, 6, 5> TracelessBasis() {
  Eigen::Matrix<double, 6, 5> t = Eigen::Matrix<double, 6, 5>::Zero();
  const double r2 = 1.0 / std::sqrt(2.0), r6 = 1.0 / std::sqrt(6.0);
  t.col(0).head<3>() << r2, -r2, 0.0;
  t.col(1).head<3>() << r6, r6, -2.0 * r6;
  t(3, 2) = r2;
  t(4, 3) = r2;
  t(5, 4) = r2;
  return t;
}

}  // namespace

SoftIronFit FitSoftIron(const MagCalibrationSums& sums, const SoftIronLimits& limits) {
  SoftIronFit fit;
  if (sums.s0 < kMinWeight) return fit;
  const Matrix12d n = NormalMatrix(sums);
  // theta = theta_0 + G phi, theta_0 = (1, 1, 1, 0, ...), G = blockdiag(T, I_6): H = G^T N G
  // and G^T N theta_0 written per block (G's identity block costs nothing).
  static const Eigen::Matrix<double, 6, 5> t = TracelessBasis();
  Vector12d theta0 = Vector12d::Zero();
  theta0.head<3>().setOnes();
  Matrix11d h;
  const Eigen::Matrix<double, 6, 5> n_aa_t = n.topLeftCorner<6, 6>() * t;
  h.topLeftCorner<5, 5>() = t.transpose() * n_aa_t;
  h.bottomLeftCorner<6, 5>() = n.bottomLeftCorner<6, 6>() * t;
  h.topRightCorner<5, 6>() = h.bottomLeftCorner<6, 5>().transpose();
  h.bottomRightCorner<6, 6>() = n.bottomRightCorner<6, 6>();
  const Vector12d n_theta0 = n.leftCols<3>().rowwise().sum();  // N theta_0
  Vector11d gt_n_theta0;
  gt_n_theta0.head<5>() = t.transpose() * n_theta0.head<6>();
  gt_n_theta0.tail<6>() = n_theta0.tail<6>();
  // The offset and world-field block must be invertible (the hard-iron fit's condition).
  const Eigen::LLT<Eigen::Matrix<double, 6, 6>> rr(h.bottomRightCorner<6, 6>());
  if (rr.info() != Eigen::Success) return fit;
  const Eigen::Matrix<double, 6, 5> rr_re = rr.solve(h.bottomLeftCorner<6, 5>());
  const Eigen::Matrix<double, 5, 5> d = h.topLeftCorner<5, 5>() - h.topRightCorner<5, 6>() * rr_re;
  const Eigen::LDLT<Matrix11d> ldlt(h);
  if (ldlt.info() != Eigen::Success) return fit;
  const Vector11d phi = ldlt.solve(-gt_n_theta0);
  Vector12d theta = theta0;
  theta.head<6>() += t * phi.head<5>();
  theta.tail<6>() += phi.tail<6>();
  const Eigen::Matrix<double, 6, 1> a = theta.head<6>();
  fit.correction << a(0), a(3), a(4), a(3), a(1), a(5), a(4), a(5), a(2);
  fit.field_world_uT = theta.tail<3>();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> a_eigen;
  a_eigen.computeDirect(fit.correction, Eigen::EigenvaluesOnly);
  fit.distortion = (a_eigen.eigenvalues().array() - 1.0).abs().maxCoeff();
  if (a_eigen.eigenvalues()(0) <= 0.0) return fit;  // not a distortion at all
  fit.offset_uT = fit.correction.inverse() * theta.segment<3>(6);
  fit.residual_uT = std::sqrt(std::max(0.0, theta.dot(n * theta) / sums.s0));
  const double field2 = fit.field_world_uT.squaredNorm();
  if (field2 <= 0.0) return fit;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 5, 5>> d_eigen(d, Eigen::EigenvaluesOnly);
  fit.diversity = std::max(0.0, 3.0 * d_eigen.eigenvalues()(0) / (sums.s0 * field2));
  const double allowed_uT = limits.max_residual * std::sqrt(field2) + kAttitudeSdRad * fit.offset_uT.norm();
  fit.trusted =
      fit.diversity >= limits.min_diversity && fit.residual_uT <= allowed_uT && fit.distortion <= limits.max_distortion;
  return fit;
}

}  // namespace localizer::engine
