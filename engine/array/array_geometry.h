// Sensor array geometry and the TDOA measurement model.
//
// Sensors m_0..m_{N-1} (N >= 4) in one right-handed world frame, metres; sound speed c.
// Pairs are (reference, k) for every k != reference, in ascending k; pair p is sensor
// sensor_of_pair(p). For a source at s the model is
//     h_p(s) = (|s - m_k| - |s - m_ref|) / c                      [seconds]
// with Jacobian row
//     dh_p/ds = (u_k - u_ref)^T / c,  u_i = (s - m_i) / |s - m_i|  [s/m]
// and |h_p| <= |m_k - m_ref| / c (the triangle inequality): max_delay_s(p).
//
// Geometry is rejected when it cannot localise in 3-D: fewer than 4 sensors, coincident
// sensors, or all sensors (nearly) coplanar; the smallest singular value of the centred
// sensor matrix must exceed 1e-3 of the largest (and 1 mm). Immutable and thread-safe.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "engine/core/status.h"
#include "engine/core/types.h"

namespace localizer::engine {

class ArrayGeometry {
 public:
  static StatusOr<ArrayGeometry> Create(std::vector<Vec3> sensors_m, double sound_speed_mps, int reference_sensor = 0);

  int sensor_count() const { return static_cast<int>(sensors_m_.size()); }
  int pair_count() const { return sensor_count() - 1; }
  int reference_sensor() const { return reference_; }
  double sound_speed_mps() const { return sound_speed_mps_; }
  const std::vector<Vec3>& sensors_m() const { return sensors_m_; }
  const Vec3& sensor_m(int k) const { return sensors_m_[k]; }
  int sensor_of_pair(int pair) const { return pair < reference_ ? pair : pair + 1; }
  // The pair whose non-reference sensor is `sensor` (the inverse of sensor_of_pair); -1 for
  // the reference itself.
  int pair_of_sensor(int sensor) const {
    return sensor == reference_ ? -1 : (sensor < reference_ ? sensor : sensor - 1);
  }
  // Largest |delay| any source position can produce on this pair.
  double max_delay_s(int pair) const { return max_delay_s_[pair]; }
  Vec3 centroid_m() const;
  // Largest distance between two sensors.
  double aperture_m() const;
  // The same array after a rigid motion: m_k -> rotation m_k + translation_m (a platform
  // carrying the array, `rotation` body -> world). A rigid motion keeps every distance, so
  // the copy needs no new validation and its pair delay bounds are unchanged.
  ArrayGeometry Moved(const Mat3& rotation, const Vec3& translation_m) const;

  // h(s): TDOA per pair, seconds.
  Eigen::VectorXd Tdoa(const Vec3& source_m) const;
  // dh/ds: pair_count x 3, seconds per metre.
  Eigen::MatrixXd TdoaJacobian(const Vec3& source_m) const;
  // Propagation time from the source to sensor k, seconds.
  double TravelTime(const Vec3& source_m, int k) const;

 private:
  ArrayGeometry() = default;
  std::vector<Vec3> sensors_m_;
  std::vector<double> max_delay_s_;
  double sound_speed_mps_ = 0.0;
  int reference_ = 0;
};

}  // namespace localizer::engine
