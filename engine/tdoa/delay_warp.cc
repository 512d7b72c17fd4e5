#include "engine/tdoa/delay_warp.h"

#include <algorithm>
#include <cmath>

namespace localizer::engine {
namespace {

// Catmull-Rom: passes through p1 at t = 0 and p2 at t = 1 with central-difference slopes.
inline float CatmullRom(float p0, float p1, float p2, float p3, float t) {
  const float a = -0.5f * p0 + 1.5f * p1 - 1.5f * p2 + 0.5f * p3;
  const float b = p0 - 2.5f * p1 + 2.0f * p2 - 0.5f * p3;
  const float c = -0.5f * p0 + 0.5f * p2;
  return ((a * t + b) * t + c) * t + p1;
}

}  // namespace

void WarpChannel(const float* in, int n_samples, double rate, float* out) {
  const double centre = 0.5 * (n_samples - 1);
  const int last = n_samples - 1;
  const auto at = [&](int i) { return in[std::clamp(i, 0, last)]; };
  for (int n = 0; n < n_samples; ++n) {
    const double x = n + rate * (n - centre);
    if (x >= 1.0 && x < last - 2) {  // all four taps inside: no clamping, floor by truncation
      const auto i = static_cast<int>(x);
      out[n] = CatmullRom(in[i - 1], in[i], in[i + 1], in[i + 2], static_cast<float>(x - i));
      continue;
    }
    const double floor_x = std::floor(x);
    const auto i = static_cast<int>(floor_x);
    out[n] = CatmullRom(at(i - 1), at(i), at(i + 1), at(i + 2), static_cast<float>(x - floor_x));
  }
}

}  // namespace localizer::engine
