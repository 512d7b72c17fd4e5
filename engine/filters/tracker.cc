#include "engine/filters/tracker.h"

#include <cmath>
#include <string>

namespace localizer::engine {

Status ValidateMovedArray(const ArrayGeometry& current, const ArrayGeometry& moved) {
  if (moved.sensor_count() != current.sensor_count() || moved.reference_sensor() != current.reference_sensor() ||
      moved.sound_speed_mps() != current.sound_speed_mps()) {
    return InvalidArgument("moved array has " + std::to_string(moved.sensor_count()) + " sensors, reference " +
                           std::to_string(moved.reference_sensor()) + ", c " + std::to_string(moved.sound_speed_mps()) +
                           " m/s; the tracker's has " + std::to_string(current.sensor_count()) + ", " +
                           std::to_string(current.reference_sensor()) + ", " +
                           std::to_string(current.sound_speed_mps()));
  }
  for (int i = 0; i < current.sensor_count(); ++i) {
    for (int j = 0; j < i; ++j) {
      const double before = (current.sensor_m(i) - current.sensor_m(j)).norm();
      const double after = (moved.sensor_m(i) - moved.sensor_m(j)).norm();
      if (!(std::abs(after - before) <= 1e-3)) {
        return InvalidArgument("moved array is not a rigid motion of the tracker's: sensors " + std::to_string(j) +
                               " and " + std::to_string(i) + " are " + std::to_string(after) + " m apart, were " +
                               std::to_string(before) + " m");
      }
    }
  }
  return Status::Ok();
}

}  // namespace localizer::engine
