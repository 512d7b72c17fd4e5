// A position fix from one set of TDOAs: closed form, then Levenberg–Marquardt.
//
// Closed form (spherical intersection, Smith & Abel 1987 / Chan & Ho 1994 in spirit): with
// the reference sensor at the origin, x_k = m_k - m_ref, delta_k = c d_k and r = |s|,
// squaring |s - x_k| = r + delta_k gives equations linear in s for a given r:
//     x_k . s + delta_k r = (|x_k|^2 - delta_k^2) / 2            (one per pair)
// Least squares gives s = a + b r; substituting into |s|^2 = r^2 leaves a quadratic in r
// whose non-negative roots are the candidates (two for 4 sensors may both fit exactly).
// Each candidate is refined by Levenberg–Marquardt on
//     J(s) = sum_k ((h_k(s) - d_k) / sigma)^2
// and the lowest cost wins (ties within 1e-9 go to the candidate nearest `hint_m` when
// given, else to the one nearer the array).
// Covariance: sigma^2 (H^T H)^-1 with H = dh/ds at the fix (the Cramer–Rao bound for
// independent TDOA errors of standard deviation sigma).
// Cost: a few hundred flops per iteration, ~10 iterations. Thread-safe (pure function).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "engine/array/array_geometry.h"

namespace localizer::engine {

struct Fix {
  Vec3 position_m = Vec3::Zero();
  Mat3 covariance_m2 = Mat3::Zero();
  double rms_residual_s = 0.0;  // RMS of h(s) - d at the fix
  int iterations = 0;           // LM iterations of the winning candidate
  bool converged = false;       // LM met its step tolerance before max_iterations
  // sqrt(trace(covariance)): one-number accuracy of the fix.
  double position_std_m() const { return std::sqrt(covariance_m2.trace()); }
};

struct MultilaterationOptions {
  double tdoa_sigma_s = 20e-6;   // per-pair TDOA standard deviation, > 0
  int max_iterations = 50;       // LM iterations per candidate
  const Vec3* hint_m = nullptr;  // optional prior position to break ties
};

// INVALID_ARGUMENT if tdoa_s has the wrong size or non-finite values; FAILED_PRECONDITION
// if no candidate converges to a finite position.
StatusOr<Fix> Multilaterate(const ArrayGeometry& array, const Eigen::VectorXd& tdoa_s,
                            const MultilaterationOptions& options = {});

// The closed form's candidate positions for these TDOAs (above; the reference sensor's
// range r from the quadratic's non-negative roots): two for a 4-sensor array wherever the
// TDOAs have two exact solutions, least-squares starting points otherwise. Unrefined.
std::vector<Vec3> ClosedFormCandidates(const ArrayGeometry& array, const Eigen::VectorXd& tdoa_s);

// Position covariance that TDOAs of standard deviation sigma allow at `source_m`:
// sigma^2 (H^T H)^-1, H = dh/ds. Its trace's square root is the per-fix position CRLB.
Mat3 TdoaPositionCrlb(const ArrayGeometry& array, const Vec3& source_m, double tdoa_sigma_s);
// The same with one standard deviation per pair (R = diag(sigma_s^2)): (H^T R^-1 H)^-1.
Mat3 TdoaPositionCrlb(const ArrayGeometry& array, const Vec3& source_m, const Eigen::VectorXd& sigma_s);

}  // namespace localizer::engine
