#include "engine/tdoa/delay_warp.h"

#include <algorithm>
#include <cmath>

namespace localizer::engine {

void WarpChannel(const float* in, int n_samples, double rate, float* out) {
  const double centre = 0.5 * (n_samples - 1);
  const int last = n_samples - 1;
  const auto at = [&](int i) { return in[std::clamp(i, 0, last)]; };
  for (int n = 0; n < n_samples; ++n) {
    const double x = n + rate * (n - centre);
    const double floor_x = std::floor(x);
    const auto i = static_cast<int>(floor_x);
    const auto t = static_cast<float>(x - floor_x);
    const float p0 = at(i - 1), p1 = at(i), p2 = at(i + 1), p3 = at(i + 2);
    // Catmull-Rom: passes through p1 at t = 0 and p2 at t = 1 with central-difference slopes.
    const float a = -0.5f * p0 + 1.5f * p1 - 1.5f * p2 + 0.5f * p3;
    const float b = p0 - 2.5f * p1 + 2.0f * p2 - 0.5f * p3;
    const float c = -0.5f * p0 + 0.5f * p2;
    out[n] = ((a * t + b) * t + c) * t + p1;
  }
}

}  // namespace localizer::engine
