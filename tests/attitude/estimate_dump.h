// ATT_DUMP=path: every estimate the attitude tests' runners see is appended to `path` as 10
// raw doubles (quaternion w x y z, the Euler stds, the gyro bias), so a change meant to move
// no result (a cheaper update) can be compared bit for bit with the code before it:
//   ATT_DUMP=/tmp/before.bin build/tests/broad_test   (then after, then compare the files)
// Unset: nothing is written.
#pragma once

#include <cstdio>
#include <cstdlib>

#include "engine/attitude/attitude_filter.h"

namespace localizer::engine::testing {

inline void DumpEstimate(const AttitudeEstimate& e) {
  static std::FILE* const file = [] {
    const char* path = std::getenv("ATT_DUMP");
    return path != nullptr ? std::fopen(path, "ab") : nullptr;
  }();
  if (file == nullptr) return;
  const double row[10] = {e.body_to_world.w(), e.body_to_world.x(), e.body_to_world.y(), e.body_to_world.z(),
                          e.sd_rad.x(),        e.sd_rad.y(),        e.sd_rad.z(),        e.gyro_bias_rps.x(),
                          e.gyro_bias_rps.y(), e.gyro_bias_rps.z()};
  std::fwrite(row, sizeof row, 1, file);
}

}  // namespace localizer::engine::testing
