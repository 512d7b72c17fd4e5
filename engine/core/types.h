// Shared value types: the state vector layout and fixed-size Eigen aliases.
#pragma once

#include <Eigen/Core>

namespace localizer::engine {

using Vec3 = Eigen::Vector3d;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat3 = Eigen::Matrix3d;
using Mat6 = Eigen::Matrix<double, 6, 6>;

// Tracker state: position then velocity in the world frame, (x, y, z, vx, vy, vz),
// metres and metres per second.
enum StateIndex { kX = 0, kY, kZ, kVx, kVy, kVz, kStateSize };

}  // namespace localizer::engine
