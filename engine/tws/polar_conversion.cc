#include "engine/tws/polar_conversion.h"

#include <cmath>

namespace localizer::engine::tws {

Converted3 ConvertSpherical(double range_m, double bearing_rad, double elevation_rad, const PolarNoise& noise,
                            Conversion method) {
  const double r = range_m, theta = bearing_rad, phi = elevation_rad;
  const double ct = std::cos(theta), st = std::sin(theta);
  const double cp = std::cos(phi), sp = std::sin(phi);
  const double sr2 = noise.range_sigma_m * noise.range_sigma_m;
  const double stt = noise.bearing_sigma_rad * noise.bearing_sigma_rad;
  const double spp = noise.elevation_sigma_rad * noise.elevation_sigma_rad;
  Converted3 out;
  if (method == Conversion::kNaive) {
    out.position_m = r * Eigen::Vector3d(cp * ct, cp * st, sp);
    Eigen::Matrix3d j;                         // columns: d/dr, d/dtheta, d/dphi
    j << cp * ct, -r * cp * st, -r * sp * ct,  //
        cp * st, r * cp * ct, -r * sp * st,    //
        sp, 0.0, r * cp;
    out.covariance_m2 = j * Eigen::Vector3d(sr2, stt, spp).asDiagonal() * j.transpose();
    return out;
  }
  const double lt = std::exp(-0.5 * stt);
  const double lp = std::exp(-0.5 * spp);
  const double a = lp * lp * lp * lp;
  const double b = lt * lt * lt * lt;
  const Eigen::Vector3d u = r * Eigen::Vector3d(cp * ct / (lt * lp), cp * st / (lt * lp), sp / lp);
  const Eigen::Vector3d m = r * Eigen::Vector3d(lt * lp * cp * ct, lt * lp * cp * st, lp * sp);
  const double rho = r * r + sr2;
  const double c2p = std::cos(2.0 * phi), s2p = std::sin(2.0 * phi);
  const double c2t = std::cos(2.0 * theta), s2t = std::sin(2.0 * theta);
  Eigen::Matrix3d second;  // E[t t^T | z]
  second(0, 0) = 0.25 * rho * (1.0 + a * c2p) * (1.0 + b * c2t);
  second(1, 1) = 0.25 * rho * (1.0 + a * c2p) * (1.0 - b * c2t);
  second(2, 2) = 0.5 * rho * (1.0 - a * c2p);
  second(0, 1) = second(1, 0) = 0.25 * rho * (1.0 + a * c2p) * b * s2t;
  second(0, 2) = second(2, 0) = 0.5 * rho * a * s2p * lt * ct;
  second(1, 2) = second(2, 1) = 0.5 * rho * a * s2p * lt * st;
  out.position_m = u;
  out.covariance_m2 = u * u.transpose() - u * m.transpose() - m * u.transpose() + second;
  return out;
}

Converted2 ConvertPolar(double range_m, double bearing_rad, const PolarNoise& noise, Conversion method) {
  const double r = range_m, theta = bearing_rad;
  const double ct = std::cos(theta), st = std::sin(theta);
  const double sr2 = noise.range_sigma_m * noise.range_sigma_m;
  const double stt = noise.bearing_sigma_rad * noise.bearing_sigma_rad;
  Converted2 out;
  if (method == Conversion::kNaive) {
    out.position_m = r * Eigen::Vector2d(ct, st);
    Eigen::Matrix2d j;
    j << ct, -r * st, st, r * ct;
    out.covariance_m2 = j * Eigen::Vector2d(sr2, stt).asDiagonal() * j.transpose();
    return out;
  }
  // The spherical formulas at phi = 0, sigma_p = 0, written out for the hot path.
  const double lt = std::exp(-0.5 * stt);
  const double b = lt * lt * lt * lt;
  const double rho = r * r + sr2;
  const double c2t = 2.0 * ct * ct - 1.0, s2t = 2.0 * st * ct;
  const double k = (1.0 / (lt * lt) - 2.0) * r * r;  // u u^T - u m^T - m u^T = k (c, s)(c, s)^T
  out.position_m = (r / lt) * Eigen::Vector2d(ct, st);
  out.covariance_m2(0, 0) = k * ct * ct + 0.5 * rho * (1.0 + b * c2t);
  out.covariance_m2(1, 1) = k * st * st + 0.5 * rho * (1.0 - b * c2t);
  out.covariance_m2(0, 1) = out.covariance_m2(1, 0) = k * ct * st + 0.5 * rho * b * s2t;
  return out;
}

}  // namespace localizer::engine::tws
