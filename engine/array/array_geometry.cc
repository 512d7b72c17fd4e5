#include "engine/array/array_geometry.h"

#include <Eigen/SVD>
#include <cmath>
#include <string>

namespace localizer::engine {

StatusOr<ArrayGeometry> ArrayGeometry::Create(std::vector<Vec3> sensors_m, double sound_speed_mps,
                                              int reference_sensor) {
  const int n = static_cast<int>(sensors_m.size());
  if (n < 4) {
    return InvalidArgument("array has " + std::to_string(n) + " sensors; 3-D localisation needs at least 4");
  }
  if (!(sound_speed_mps > 0.0) || !std::isfinite(sound_speed_mps)) {
    return InvalidArgument("sound_speed_mps must be positive and finite, got " + std::to_string(sound_speed_mps));
  }
  if (reference_sensor < 0 || reference_sensor >= n) {
    return InvalidArgument("reference sensor " + std::to_string(reference_sensor) + " is not in 0.." +
                           std::to_string(n - 1));
  }
  for (int i = 0; i < n; ++i) {
    if (!sensors_m[i].allFinite()) {
      return InvalidArgument("sensor " + std::to_string(i) + " has a non-finite coordinate");
    }
    for (int j = 0; j < i; ++j) {
      if ((sensors_m[i] - sensors_m[j]).norm() < 1e-3) {
        return InvalidArgument("sensors " + std::to_string(j) + " and " + std::to_string(i) +
                               " coincide (closer than 1 mm)");
      }
    }
  }
  Vec3 centroid = Vec3::Zero();
  for (const Vec3& m : sensors_m) centroid += m;
  centroid /= n;
  Eigen::MatrixXd centred(n, 3);
  for (int i = 0; i < n; ++i) centred.row(i) = (sensors_m[i] - centroid).transpose();
  const Eigen::Vector3d sv = Eigen::JacobiSVD<Eigen::MatrixXd>(centred).singularValues();
  if (sv(2) < 1e-3 * sv(0) || sv(2) < 1e-3) {
    return InvalidArgument(
        "array geometry is degenerate: the sensors are (nearly) coplanar or collinear "
        "(singular values " +
        std::to_string(sv(0)) + ", " + std::to_string(sv(1)) + ", " + std::to_string(sv(2)) +
        " m); 3-D localisation needs sensors off a common plane");
  }
  ArrayGeometry g;
  g.sensors_m_ = std::move(sensors_m);
  g.sound_speed_mps_ = sound_speed_mps;
  g.reference_ = reference_sensor;
  for (int p = 0; p < g.pair_count(); ++p) {
    g.max_delay_s_.push_back((g.sensors_m_[g.sensor_of_pair(p)] - g.sensors_m_[reference_sensor]).norm() /
                             sound_speed_mps);
  }
  return g;
}

ArrayGeometry ArrayGeometry::Moved(const Mat3& rotation, const Vec3& translation_m) const {
  ArrayGeometry moved = *this;
  for (Vec3& m : moved.sensors_m_) m = rotation * m + translation_m;
  return moved;
}

Vec3 ArrayGeometry::centroid_m() const {
  Vec3 c = Vec3::Zero();
  for (const Vec3& m : sensors_m_) c += m;
  return c / sensor_count();
}

double ArrayGeometry::aperture_m() const {
  double best = 0.0;
  for (int i = 0; i < sensor_count(); ++i)
    for (int j = 0; j < i; ++j) best = std::max(best, (sensors_m_[i] - sensors_m_[j]).norm());
  return best;
}

Eigen::VectorXd ArrayGeometry::Tdoa(const Vec3& s) const {
  Eigen::VectorXd h(pair_count());
  const double r_ref = (s - sensors_m_[reference_]).norm();
  for (int p = 0; p < pair_count(); ++p) {
    h(p) = ((s - sensors_m_[sensor_of_pair(p)]).norm() - r_ref) / sound_speed_mps_;
  }
  return h;
}

Eigen::MatrixXd ArrayGeometry::TdoaJacobian(const Vec3& s) const {
  Eigen::MatrixXd jac(pair_count(), 3);
  const Vec3 d_ref = s - sensors_m_[reference_];
  const Vec3 u_ref = d_ref / std::max(d_ref.norm(), 1e-9);
  for (int p = 0; p < pair_count(); ++p) {
    const Vec3 d = s - sensors_m_[sensor_of_pair(p)];
    const Vec3 u = d / std::max(d.norm(), 1e-9);
    jac.row(p) = ((u - u_ref) / sound_speed_mps_).transpose();
  }
  return jac;
}

double ArrayGeometry::TravelTime(const Vec3& s, int k) const { return (s - sensors_m_[k]).norm() / sound_speed_mps_; }

}  // namespace localizer::engine
