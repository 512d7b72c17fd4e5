// Converted measurements: a (range, bearing[, elevation]) plot as a Cartesian position with
// a covariance, so that a linear Kalman filter can use it (Stone Soup's measurement-model
// role for the tracker: CartesianToBearingRange's inverse, done once per plot).
//
// Angles follow engine/core/detection.h: bearing theta in x-y from +x towards +y,
// elevation phi from that plane towards +z. Noise: r = r_t + w_r, theta = theta_t + w_t,
// phi = phi_t + w_p, independent zero-mean Gaussians with std sigma_r, sigma_t, sigma_p.
//
// kNaive:     u = r (cos phi cos theta, cos phi sin theta, sin phi);  R = J diag(s^2) J^T,
//             J = du/d(r, theta, phi) at the measurement. Biased: E[u] = lambda_t lambda_p
//             r_t (...) shrinks towards the sensor when sigma_t r / sigma_r is large.
// kUnbiased:  the unbiased converted measurement of Mo, Song, Zhou, Sun & Bar-Shalom (1998),
//             with the covariance as corrected by Duan, Han & Li (2004), evaluated at the
//             measurement. lambda_t = E[cos w_t] = exp(-sigma_t^2 / 2), lambda_p likewise:
//               u = r (cos phi cos theta / (lt lp), cos phi sin theta / (lt lp), sin phi / lp)
//               R_ij = u_i u_j - u_i m_j - m_i u_j + E[t_i t_j | z]
//             where t is the true position given the plot and m = E[t | z] =
//             r (lt lp cos phi cos theta, lt lp cos phi sin theta, lp sin phi); with
//             rho = r^2 + sigma_r^2, a = lp^4, b = lt^4 (= E[cos 2w]):
//               E[t_x^2] = rho (1 + a cos 2phi)(1 + b cos 2theta) / 4
//               E[t_y^2] = rho (1 + a cos 2phi)(1 - b cos 2theta) / 4
//               E[t_z^2] = rho (1 - a cos 2phi) / 2
//               E[t_x t_y] = rho (1 + a cos 2phi) b sin 2theta / 4
//               E[t_x t_z] = rho a sin 2phi lt cos theta / 2,  E[t_y t_z] = ... sin theta / 2
//             The 2-D case is phi = 0, sigma_p = 0 (lp = a = 1). E[u] = t (unbiased) and R is
//             the conditional second moment of u - t given the plot, so the NEES of u is
//             about dim z (tests/tws/polar_conversion_test.cc measures both).
// Positions are relative to the sensor; add the sensor's world position. Cost: ~30 flops
// and three sin/cos pairs per plot.
#pragma once

#include <Eigen/Core>

namespace localizer::engine::tws {

enum class Conversion { kNaive, kUnbiased };

struct PolarNoise {
  double range_sigma_m = 10.0;        // sigma_r >= 0
  double bearing_sigma_rad = 0.01;    // sigma_t >= 0
  double elevation_sigma_rad = 0.01;  // sigma_p >= 0 (spherical plots only)
};

struct Converted2 {
  Eigen::Vector2d position_m;
  Eigen::Matrix2d covariance_m2;
};
struct Converted3 {
  Eigen::Vector3d position_m;
  Eigen::Matrix3d covariance_m2;
};

// (range, bearing) -> (x, y) relative to the sensor.
Converted2 ConvertPolar(double range_m, double bearing_rad, const PolarNoise& noise, Conversion method);
// (range, bearing, elevation) -> (x, y, z) relative to the sensor.
Converted3 ConvertSpherical(double range_m, double bearing_rad, double elevation_rad, const PolarNoise& noise,
                            Conversion method);

}  // namespace localizer::engine::tws
