#include "engine/models/singer.h"

#include <algorithm>
#include <cmath>

#include "engine/models/constant_acceleration.h"

namespace localizer::engine {
namespace {

// Q1 / (2 alpha sigma_m^2) = int_0^T g g^T, g(tau) = (phi13, phi23, phi33)(tau) the last column
// of the transition, from the power series of g in tau (alternating, terms ~ (alpha T)^k / k!,
// so 24 terms reach rounding for alpha T < 0.5):
//   phi33 = sum_{k>=0} (-alpha)^k tau^k / k!,   phi23 = sum_{k>=1} (-alpha)^{k-1} tau^k / k!,
//   phi13 = sum_{k>=2} (-alpha)^{k-2} tau^k / k!.
Eigen::Matrix3d SeriesNoise(double a, double t) {
  constexpr int kTerms = 24;
  double c[3][kTerms] = {};
  double factorial = 1.0, power = 1.0;  // k!, (-alpha)^k
  for (int k = 0; k < kTerms; ++k) {
    if (k > 0) factorial *= k;
    c[2][k] = power / factorial;
    if (k + 1 < kTerms) c[1][k + 1] = power / (factorial * (k + 1));
    if (k + 2 < kTerms) c[0][k + 2] = power / (factorial * (k + 1) * (k + 2));
    power *= -a;
  }
  Eigen::Matrix3d q;
  for (int i = 0; i < 3; ++i) {
    for (int j = i; j < 3; ++j) {
      double sum = 0.0;
      for (int m = 2 * kTerms - 2; m >= 0; --m) {  // int tau^m = T^(m+1) / (m+1), by Horner
        double coeff = 0.0;
        for (int p = std::max(0, m - kTerms + 1); p <= std::min(m, kTerms - 1); ++p) coeff += c[i][p] * c[j][m - p];
        sum = sum * t + coeff / (m + 1);
      }
      q(i, j) = q(j, i) = sum * t;
    }
  }
  return q;
}

}  // namespace

Eigen::Matrix3d SingerModel::AxisTransition(double dt_s) const {
  const double t = dt_s;
  const double a = alpha_, e = std::exp(-a * t);
  Eigen::Matrix3d f;
  // (alpha T - 1 + e) / alpha^2 and (1 - e) / alpha lose digits for small alpha T: expm1.
  const double em1 = std::expm1(-a * t);  // e - 1
  f << 1.0, t, (a * t + em1) / (a * a), 0.0, 1.0, -em1 / a, 0.0, 0.0, e;
  return f;
}

Eigen::Matrix3d SingerModel::AxisNoise(double dt_s) const {
  const double t = dt_s;
  const double a = alpha_, at = a * t;
  if (at < 0.5) {  // the closed forms cancel here: integrate the power series instead
    return 2.0 * a * sigma_m_ * sigma_m_ * SeriesNoise(a, t);
  } else {
    const double e = std::exp(-at), e2 = e * e;
    double q11, q12, q13, q22, q23, q33;
    const double a2 = a * a, a3 = a2 * a, a4 = a3 * a, a5 = a4 * a;
    q11 = (1.0 - e2 + 2.0 * at + 2.0 * at * at * at / 3.0 - 2.0 * at * at - 4.0 * at * e) / (2.0 * a5);
    q12 = (e2 + 1.0 - 2.0 * e + 2.0 * at * e - 2.0 * at + at * at) / (2.0 * a4);
    q13 = (1.0 - e2 - 2.0 * at * e) / (2.0 * a3);
    q22 = (4.0 * e - 3.0 - e2 + 2.0 * at) / (2.0 * a3);
    q23 = (e2 + 1.0 - 2.0 * e) / (2.0 * a2);
    q33 = (1.0 - e2) / (2.0 * a);
    Eigen::Matrix3d q;
    q << q11, q12, q13, q12, q22, q23, q13, q23, q33;
    return 2.0 * a * sigma_m_ * sigma_m_ * q;
  }
}

Eigen::VectorXd SingerModel::Propagate(const Eigen::VectorXd& x, double dt_s) const {
  return KronAxes(AxisTransition(dt_s)) * x;
}

Eigen::MatrixXd SingerModel::Jacobian(const Eigen::VectorXd&, double dt_s) const {
  return KronAxes(AxisTransition(dt_s));
}

Eigen::MatrixXd SingerModel::ProcessNoise(const Eigen::VectorXd&, double dt_s) const {
  return KronAxes(AxisNoise(dt_s));
}

}  // namespace localizer::engine
