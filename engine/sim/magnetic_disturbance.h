// Magnetic disturbances added to an IMU recording (real or synthetic), so the attitude
// filters can be tested against the fields that break magnetometer-aided heading:
//
//  - a magnet (or iron) riding on the sensor: from start_s on, the body-frame reading becomes
//        m' = soft_iron m + offset_uT
//    (hard iron = a constant body-frame offset, soft iron = a matrix near the identity), the
//    case of BROAD's "magnet attached to the IMU" trials; start_s at or before the first
//    sample puts it there the whole time;
//  - a field that bends near a ferrous object fixed in the world, passed by the sensor: a
//    world-frame field added with a Gaussian envelope in time,
//        m' = m + R(t)^T peak_world_uT exp(-(t - centre_s)^2 / (2 width_s^2)),
//    R(t) the true body -> world rotation (samples whose truth is not finite are left alone;
//    beyond 4 widths from the centre nothing is added).
//
// Samples without a finite magnetometer reading are left alone. Draws come from a generator
// seeded by the caller's seed alone (engine/sim/seeding.h conventions): same seed, same case.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "engine/core/imu.h"

namespace localizer::engine {

struct BodyFixedMagnet {
  Eigen::Vector3d offset_uT = Eigen::Vector3d::Zero();      // hard iron, body frame
  Eigen::Matrix3d soft_iron = Eigen::Matrix3d::Identity();  // applied before the offset
  double start_s = 0.0;                                     // from this sample time on
};

struct PassingObject {
  Eigen::Vector3d peak_world_uT = Eigen::Vector3d::Zero();  // added field at the closest pass
  double centre_s = 0.0;
  double width_s = 1.0;  // > 0: the field bends over a few widths
};

// A magnet of `offset_norm_uT` in a direction drawn uniformly on the sphere, with a soft-iron
// matrix I + E, E symmetric with entries uniform in [-soft_iron_fraction, soft_iron_fraction].
BodyFixedMagnet RandomBodyFixedMagnet(double offset_norm_uT, double soft_iron_fraction, double start_s, uint64_t seed);

// Iron riding on the sensor with a magnet: a soft-iron matrix S = Q diag(1 + d) Q^T with
// principal gains d_i uniform in [-gain_fraction, gain_fraction] along principal axes Q drawn
// uniformly over the rotations (gain_fraction 0.05: "±5 % soft iron"), and a hard-iron offset of
// `offset_norm_uT` in a direction uniform on the sphere. Unlike RandomBodyFixedMagnet, whose
// entries are drawn independently, the departure from the identity is bounded by gain_fraction
// along every axis, so the case says how large a distortion it is.
BodyFixedMagnet RandomSoftIronMagnet(double offset_norm_uT, double gain_fraction, double start_s, uint64_t seed);

// An object whose field at the closest pass has norm `peak_norm_uT`, direction uniform on the
// sphere.
PassingObject RandomPassingObject(double peak_norm_uT, double centre_s, double width_s, uint64_t seed);

void AddBodyFixedMagnet(const BodyFixedMagnet& magnet, std::vector<ImuSample>* samples);

// body_to_world[i] is the true attitude of samples[i] (same length; NaN where unknown).
void AddPassingObject(const PassingObject& object, const std::vector<Eigen::Quaterniond>& body_to_world,
                      std::vector<ImuSample>* samples);

}  // namespace localizer::engine
