// Online soft-iron estimation: the symmetric distortion that iron riding on the sensor (or a
// magnetometer's own axis gains and cross-talk) applies to the body-frame field, fitted with
// the hard-iron offset over the window the hard-iron estimator already sums
// (hard_iron_estimator.h, MagCalibrationSums).
//
// Model. The reading is m_k = S R_k^T m_w + o (+ noise): the world's field m_w turned into the
// body by the attitude R_k (body -> world), distorted by S (symmetric, near I) and offset by
// o. With A = S^-1 (the correction, symmetric) and c = A o, the corrected reading is the
// world field seen from the body:
//     e_k = A m_k - c - R_k^T m_w = 0        (A m_k - c = A (m_k - o)),
// linear in the twelve unknowns theta = (a, c, m_w), a = (A11, A22, A33, A12, A13, A23). Its
// weighted sum of squares is theta^T N theta, N (12x12) built from the sums alone
// (sum w m m^T, sum w m, sum w m_i R, sum w R, sum w). A, c and m_w scaled together fit
// equally well (a field read in other units), so the scale is fixed by trace(A) = 3:
// A = I + T e, e in the 5-dimensional space of traceless symmetric matrices (T orthonormal
// in the Frobenius norm), and the fit is the unconstrained least squares in
// phi = (e, c, m_w) (11 unknowns): H phi = -G^T N theta_0, H = G^T N G. The scale does not
// matter for heading (only the corrected field's direction does). Then
//     offset o = A^-1 c,  residual^2 = theta^T N theta / S0 (mean squared misfit per sample).
// With A = I this is the hard-iron model (hard_iron_estimator.h) exactly.
//
// Confidence. diversity = 3 lambda_min(D) / (S0 |m_w|^2), D the information about e once c
// and m_w are eliminated (the Schur complement of H on e): 1 when the attitudes are spread
// over the whole sphere (there E |dA m|^2 = |m_w|^2 |dA|_F^2 / 3 for a traceless dA), 0 when a
// distortion is indistinguishable from a change of offset or world field. A turn about one
// axis is enough for a hard-iron fit but not for this one: S's part along that axis is
// unobserved. The fit is trusted when diversity >= min_diversity, the RMS residual is within
// the hard-iron fit's allowance (max_residual |m_w| + 0.01 |o|) and every eigenvalue of A is
// within max_distortion of 1 (conditioning: a fit that calls for more distortion than iron
// riding on a sensor gives is trading it for a disturbance or an attitude error).
//
// Using the gyro-tracked attitude keeps the fit linear and lets partial rotations count, as
// for the hard-iron fit. The filter's heading follows the field it corrects, which hides
// part of the distortion's horizontal effect from the world-frame misfit; the norm and the
// vertical part still see it, so the fit converges, more slowly than with the true attitude.
//
// Cost: nothing per sample beyond the hard-iron sums; one Fit() builds N (about 1,000
// multiply-adds), solves an 11x11 LDLT and a 6x6 inverse, and a 5x5 symmetric eigenvalue
// problem (~6 µs on the 2-vCPU VM, tests/bench/attitude_bench BM_SoftIronFit, about half
// of it the eigenvalues): meant to run about once a second.
#pragma once

#include <Eigen/Core>

#include "engine/attitude/hard_iron_estimator.h"

namespace localizer::engine {

struct SoftIronFit {
  Eigen::Matrix3d correction = Eigen::Matrix3d::Identity();  // A = S^-1, symmetric, trace 3
  Eigen::Vector3d offset_uT = Eigen::Vector3d::Zero();       // o, body frame
  Eigen::Vector3d field_world_uT = Eigen::Vector3d::Zero();  // m_w, world frame (the filter's)
  double diversity = 0.0;    // normalised smallest information about the distortion, ~[0, 1]
  double distortion = 0.0;   // largest |eigenvalue of A - 1|
  double residual_uT = 0.0;  // RMS misfit per sample
  bool trusted = false;
};

struct SoftIronLimits {
  double min_diversity = 0.2;
  double max_residual = 0.1;     // of |m_w|, plus 0.01 |o| (as the hard-iron fit)
  double max_distortion = 0.25;  // largest |eigenvalue of A - 1| believed
};

// The soft- and hard-iron fit over `sums` (not trusted with fewer than a few samples or
// without the rotations to separate the offset from the world field).
SoftIronFit FitSoftIron(const MagCalibrationSums& sums, const SoftIronLimits& limits);

}  // namespace localizer::engine
