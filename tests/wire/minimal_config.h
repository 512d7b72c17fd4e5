// A minimal valid SessionConfig for the wire tests: 4 sensors off a common plane in water,
// 48 kHz; every other field left for the engine's defaults.
#pragma once

#include "localizer/v1/localizer.pb.h"

namespace localizer::wire::testing {

inline v1::SessionConfig MinimalConfig() {
  v1::SessionConfig c;
  const double sensors[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (const auto& s : sensors) {
    v1::Vector3* v = c.mutable_array()->add_sensors_m();
    v->set_x(s[0]);
    v->set_y(s[1]);
    v->set_z(s[2]);
  }
  c.mutable_array()->set_sound_speed_mps(1500.0);
  c.set_sample_rate_hz(48000.0);
  return c;
}

}  // namespace localizer::wire::testing
