// Branch-free float32 exp, log and inverse normal CDF that the compiler vectorises inside
// particle loops (libm's expf/logf calls block vectorisation without -ffast-math).
// Accuracy, measured against double precision in tests/core/fast_math_test.cc:
//   FastExp: relative error < 3e-7 on [-87, 88]; clamps below -87 (no denormals, never 0).
//   FastLog: |error| < 3e-7 * max(1, |ln x|) on normal positive floats (float rounding of
//     the result dominates for large |ln x|).
//   NormalFromUniform: |error| < 2e-5 sigma for u in [1e-3, 1 - 1e-3], < 2e-3 sigma beyond
//     (u itself is float); the counter draws' extremes map to about +-5.3.
// Every function here runs on the host and on a CUDA device (host_device.h): the GPU's GCC
// kernels weigh with these FastExp / FastLog, and the GPU tests' host model draws with the
// counter hash. The host code is what it always was (the builtins the vectoriser wants); the
// device branches spell the same operations with CUDA's intrinsics.
#pragma once

#include <cstdint>

#include "engine/core/host_device.h"

namespace localizer::engine {

// e^x = 2^k * e^r with k = round(x / ln 2), |r| <= ln2 / 2; e^r by a degree-6 polynomial.
LOCALIZER_HOST_DEVICE inline float FastExp(float x) {
  x = x < -87.0f ? -87.0f : (x > 88.0f ? 88.0f : x);
#if defined(__CUDA_ARCH__)
  const float k = roundf(x * 1.44269504088896341f);
#else
  const float k = __builtin_roundf(x * 1.44269504088896341f);
#endif
  const float r = x - k * 0.693145751953125f - k * 1.428606765330187e-06f;
  float p = 1.0f / 720.0f;
  p = p * r + 1.0f / 120.0f;
  p = p * r + 1.0f / 24.0f;
  p = p * r + 1.0f / 6.0f;
  p = p * r + 0.5f;
  p = p * r + 1.0f;
  p = p * r + 1.0f;
  const int32_t bits = (static_cast<int32_t>(k) + 127) << 23;
  return p * hd::FloatFromBits(bits);
}

// log(x) = e ln2 + log(m) with m in [sqrt(1/2), sqrt(2)); log(m) = 2 atanh(t), t = (m-1)/(m+1).
LOCALIZER_HOST_DEVICE inline float FastLog(float x) {
  int32_t bits = hd::BitsFromFloat(x);
  int32_t e = ((bits >> 23) & 0xff) - 127;
  bits = (bits & 0x007fffff) | 0x3f800000;  // m in [1, 2)
  float m = hd::FloatFromBits(bits);
  const bool big = m > 1.41421356f;
  m = big ? m * 0.5f : m;
  e = big ? e + 1 : e;
  const float t = (m - 1.0f) / (m + 1.0f);
  const float t2 = t * t;
  float p = 2.0f / 9.0f;
  p = p * t2 + 2.0f / 7.0f;
  p = p * t2 + 2.0f / 5.0f;
  p = p * t2 + 2.0f / 3.0f;
  p = p * t2 + 2.0f;
  return static_cast<float>(e) * 0.693147180559945f + t * p;
}

// Standard normal quantile of u in (0, 1): sqrt(2) * erfinv(2u - 1), with M. Giles'
// single-precision erfinv ("Approximating the erfinv function", GPU Computing Gems, 2011).
LOCALIZER_HOST_DEVICE inline float NormalFromUniform(float u) {
  const float x = 2.0f * u - 1.0f;
  // 1 - x^2 written as 4u(1 - u): exact enough in the tails, where 1 - x cancels.
  float w = -FastLog(4.0f * u * (1.0f - u));
  float p;
  if (w < 5.0f) {
    w = w - 2.5f;
    p = 2.81022636e-08f;
    p = 3.43273939e-07f + p * w;
    p = -3.5233877e-06f + p * w;
    p = -4.39150654e-06f + p * w;
    p = 0.00021858087f + p * w;
    p = -0.00125372503f + p * w;
    p = -0.00417768164f + p * w;
    p = 0.246640727f + p * w;
    p = 1.50140941f + p * w;
  } else {
#if defined(__CUDA_ARCH__)
    w = sqrtf(w) - 3.0f;
#else
    w = __builtin_sqrtf(w) - 3.0f;
#endif
    p = -0.000200214257f;
    p = 0.000100950558f + p * w;
    p = 0.00134934322f + p * w;
    p = -0.00367342844f + p * w;
    p = 0.00573950773f + p * w;
    p = -0.0076224613f + p * w;
    p = 0.00943887047f + p * w;
    p = 1.00167406f + p * w;
    p = 2.83297682f + p * w;
  }
  return 1.41421356237f * p * x;
}

// Box–Muller: two independent standard normals from two uniforms in (0, 1),
//   r = sqrt(-2 ln u1),  (z1, z2) = r (cos 2 pi u2, sin 2 pi u2),
// with sin/cos of the quarter-turn fraction by Taylor polynomials (|error| < 1e-7) and the
// quadrant applied by exchanges and signs. Cheaper per normal than NormalFromUniform when
// normals are wanted in bulk; same accuracy limits from float u1 in the far tails.
LOCALIZER_HOST_DEVICE inline void NormalPairFromUniforms(float u1, float u2, float* z1, float* z2) {
#if defined(__CUDA_ARCH__)
  const float r = sqrtf(-2.0f * FastLog(u1));
  const float turns = 4.0f * u2;
  const float quadrant = floorf(turns);
#else
  const float r = __builtin_sqrtf(-2.0f * FastLog(u1));
  const float turns = 4.0f * u2;
  const float quadrant = __builtin_floorf(turns);
#endif
  const float x = (turns - quadrant) * 1.57079632679489662f;  // [0, pi/2)
  const float x2 = x * x;
  float sn = -1.0f / 39916800.0f;
  sn = sn * x2 + 1.0f / 362880.0f;
  sn = sn * x2 - 1.0f / 5040.0f;
  sn = sn * x2 + 1.0f / 120.0f;
  sn = sn * x2 - 1.0f / 6.0f;
  sn = (sn * x2 + 1.0f) * x;
  float cs = 1.0f / 479001600.0f;
  cs = cs * x2 - 1.0f / 3628800.0f;
  cs = cs * x2 + 1.0f / 40320.0f;
  cs = cs * x2 - 1.0f / 720.0f;
  cs = cs * x2 + 1.0f / 24.0f;
  cs = cs * x2 - 0.5f;
  cs = cs * x2 + 1.0f;
  // Rotate by quadrant * 90 degrees: (c, s) -> (-s, c) -> (-c, -s) -> (s, -c).
  const int q = static_cast<int>(quadrant) & 3;
  const float c = (q == 0) ? cs : (q == 1) ? -sn : (q == 2) ? -cs : sn;
  const float sv = (q == 0) ? sn : (q == 1) ? cs : (q == 2) ? -sn : -cs;
  *z1 = r * c;
  *z2 = r * sv;
}

// Counter-based uniform in (0, 1): a stateless hash of (key, counter), so draw i of step k
// of a session is the same whatever order or thread computes it (replay, vectorisation).
// 32-bit integer mixing (C. Wellons' "lowbias32" constants) vectorises with AVX2.
LOCALIZER_HOST_DEVICE inline uint32_t HashMix32(uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352dU;
  x ^= x >> 15;
  x *= 0x846ca68bU;
  x ^= x >> 16;
  return x;
}
LOCALIZER_HOST_DEVICE inline float UniformFromCounter(uint32_t key, uint32_t counter) {
  const uint32_t h = HashMix32(counter * 0x9e3779b9U + key);
  // 23 random bits, offset by half a step: (k + 0.5) / 2^23 needs 24 significant bits, which
  // float has, so the result is never exactly 0 or 1 (24 bits would round the top to 1).
  return (static_cast<float>(h >> 9) + 0.5f) * (1.0f / 8388608.0f);
}

}  // namespace localizer::engine
