// What a detecting sensor (search radar, active or passive sonar, another array's fixer)
// hands a multi-target tracker for one scan: plots in the sensor's polar frame.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

namespace localizer::engine {

// One plot. Bearing is measured in the world x-y plane from +x towards +y (mathematical
// convention, x = East, y = North); elevation from that plane towards +z (up). A plot
// without elevation is 2-D (range, bearing): the tracker works in x-y only for it.
struct Detection {
  double range_m = 0.0;
  double bearing_rad = 0.0;
  std::optional<double> elevation_rad;
  std::optional<double> snr_db;
};

// All plots of one scan (or one dwell): the instant they describe and where the sensor
// stood, in the world frame.
struct Scan {
  double time_s = 0.0;
  Eigen::Vector3d sensor_position_m = Eigen::Vector3d::Zero();
  std::vector<Detection> detections;
};

}  // namespace localizer::engine
