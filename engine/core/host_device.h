// Code that runs on both sides: the CPU engine and the CUDA kernels of gpu/ compile the same
// functions, so the two cannot drift apart (the GPU's CPU-equality tests in tests/gpu then
// check the toolchains, not hand-made copies).
//
//   LOCALIZER_HOST_DEVICE         __host__ __device__ under nvcc, nothing otherwise: the
//                                 engine compiles and runs without CUDA.
//   LOCALIZER_HOST_DEVICE_INLINE  the same plus __forceinline__ under nvcc, plain `inline`
//                                 otherwise (for the per-particle kernels' small helpers).
//   LOCALIZER_HOST_NOINLINE       [[gnu::noinline]] in CPU builds, nothing under nvcc: keeps a
//                                 shared function a call on the CPU where it was one before
//                                 it was shared. GCC contracts a * b + c into FMAs after
//                                 inlining and vectorising, so inlining a numeric function
//                                 into a new caller can move its results in the last bits;
//                                 the device inlines as it likes.
//
// A shared function may call only what both sides have: arithmetic, the C maths functions
// of the global namespace (sqrtf, fabs, cos, log, ...: on the host these are libm's, the
// same functions std:: names), and the helpers below. std:: algorithms are host-only, so
// Max / Min / Clamp restate std::max / std::min / std::clamp exactly (first argument on
// ties, the same NaN behaviour). Where the two sides need different spellings of one
// operation (a bit cast, a rounding the CPU's vectoriser wants as a builtin), the function
// branches on __CUDA_ARCH__ (defined only while nvcc compiles device code).
//
// engine/ never includes gpu/; gpu/ includes these engine headers.
#pragma once

#include <bit>
#include <cstdint>

#if defined(__CUDACC__)
#define LOCALIZER_HOST_DEVICE __host__ __device__
#define LOCALIZER_HOST_DEVICE_INLINE __host__ __device__ __forceinline__
#define LOCALIZER_HOST_NOINLINE
#else
#define LOCALIZER_HOST_DEVICE
#define LOCALIZER_HOST_DEVICE_INLINE inline
#define LOCALIZER_HOST_NOINLINE [[gnu::noinline]]
#endif

namespace localizer::engine::hd {

template <typename T>
LOCALIZER_HOST_DEVICE inline T Max(T a, T b) {
  return a < b ? b : a;
}
template <typename T>
LOCALIZER_HOST_DEVICE inline T Min(T a, T b) {
  return b < a ? b : a;
}
template <typename T>
LOCALIZER_HOST_DEVICE inline T Clamp(T v, T lo, T hi) {
  return v < lo ? lo : (hi < v ? hi : v);
}

LOCALIZER_HOST_DEVICE inline float FloatFromBits(int32_t bits) {
#if defined(__CUDA_ARCH__)
  return __int_as_float(bits);
#else
  return std::bit_cast<float>(bits);
#endif
}

LOCALIZER_HOST_DEVICE inline int32_t BitsFromFloat(float f) {
#if defined(__CUDA_ARCH__)
  return __float_as_int(f);
#else
  return std::bit_cast<int32_t>(f);
#endif
}

}  // namespace localizer::engine::hd
