// Branch-free log2 and exp2 for the PHAT-beta weighting loop.
//
// glibc's powf/logf/expf are scalar calls unless -ffast-math enables libmvec, which this
// project does not use; one powf per bin cost more than the FFTs. These inline versions
// vectorise (bit manipulation, a rational/polynomial kernel, no table) and are accurate to
// about 2e-7 relative (log2: absolute 1e-7; exp2: relative 2e-7), plenty for a weighting.
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

namespace localizer::engine {

// log2(x) for normal x > 0 (no check: zero, denormals, Inf and NaN give garbage).
inline float FastLog2(float x) {
  const std::uint32_t bits = std::bit_cast<std::uint32_t>(x);
  int exponent = static_cast<int>(bits >> 23) - 127;
  float mantissa = std::bit_cast<float>((bits & 0x007FFFFFu) | 0x3F800000u);  // [1, 2)
  // Centre the mantissa on 1, in [sqrt(1/2), sqrt(2)), so the series below converges fast.
  const bool high = mantissa > 1.41421356f;
  mantissa = high ? 0.5f * mantissa : mantissa;
  exponent += high ? 1 : 0;
  // ln(m) = 2 atanh(s) = 2 (s + s^3/3 + s^5/5 + s^7/7 + ...), s = (m - 1)/(m + 1), |s| < 0.172.
  const float s = (mantissa - 1.0f) / (mantissa + 1.0f);
  const float s2 = s * s;
  const float ln_mantissa = 2.0f * s * (1.0f + s2 * (1.0f / 3 + s2 * (1.0f / 5 + s2 * (1.0f / 7))));
  return static_cast<float>(exponent) + ln_mantissa * 1.44269504f;
}

// 2^y, with y clamped to [-126, 126] so the result stays a normal float.
inline float FastExp2(float y) {
  y = std::clamp(y, -126.0f, 126.0f);
  const float whole = std::floor(y + 0.5f);
  const float t = (y - whole) * 0.693147181f;  // |t| <= ln(2)/2
  // e^t, Taylor to t^6: remainder < 0.347^7 / 7! = 1.2e-7.
  const float e_t =
      1.0f + t * (1.0f + t * (1.0f / 2 + t * (1.0f / 6 + t * (1.0f / 24 + t * (1.0f / 120 + t * (1.0f / 720))))));
  const std::int32_t scale = static_cast<std::int32_t>(whole) << 23;
  return std::bit_cast<float>(static_cast<std::int32_t>(std::bit_cast<std::int32_t>(e_t) + scale));
}

// x^(-beta) for normal x > 0.
inline float FastPowNegative(float x, float beta) { return FastExp2(-beta * FastLog2(x)); }

}  // namespace localizer::engine
