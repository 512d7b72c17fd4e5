// Shared by the hard- and soft-iron estimator tests: a mid-latitude field, a hard-iron offset
// of tens of µT, the sample rate, and a tumbling motion whose attitudes cover the sphere well
// enough for either fit.
#pragma once

#include <Eigen/Core>

#include "engine/sim/platform_motion.h"

namespace localizer::engine::testing {

inline const Eigen::Vector3d kEarthField_uT(0.0, 17.0, -46.0);
inline const Eigen::Vector3d kOffset_uT(30.0, -45.0, 12.0);
inline constexpr double kRateHz = 100.0;

inline AttitudeTrajectory Tumbling() {
  AttitudeTrajectoryOptions motion;
  motion.amplitude_rad = {1.2, 0.9, 2.5};
  motion.frequency_hz = {0.13, 0.07, 0.05};
  return AttitudeTrajectory(motion);
}

}  // namespace localizer::engine::testing
