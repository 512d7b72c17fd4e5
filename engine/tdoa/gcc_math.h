// The per-bin and per-window maths of GCC-PHAT, written once for the CPU stage (gcc_phat.cc,
// cross_spectrum.h) and the GPU's batched kernels (gpu/tdoa/gcc_kernels.cu), which include
// this header (host_device.h). gcc_phat.h has the maths; this header has the arithmetic, in
// the order the results depend on (comparisons, floors, casts), so that the two stages agree
// to float rounding: what differs is FMA contraction and cuFFT against FFTW (~1e-6 relative,
// tests/gpu/gcc_math_test.cu).
//
//   per bin      G = W X_k conj(X_r) with W from the weighting (PHAT, PHAT-beta, SCOT; CC
//                is W = 1), and |W X_k X_r*| for the normalising sum;
//   floors       1e-12 of a power, clamped to [FLT_MIN, FLT_MAX], keep silent bins finite;
//   the window   lags wrap modulo the transform size; the main lobe is the run either side
//                of the peak that stays positive and keeps falling; quality = peak /
//                largest sidelobe, capped at 1e9.
#pragma once

#include <cfloat>
#include <cmath>

#include "engine/core/fast_math.h"
#include "engine/core/host_device.h"

namespace localizer::engine {

inline constexpr double kRelativeFloor = 1e-12;  // of the frame's mean power; see gcc_phat.h
inline constexpr float kQualityCap = 1e9f;       // peak / sidelobe never exceeds it

// One complex bin, as FFTW interleaves it (re, im).
struct CrossBin {
  float re;
  float im;
};

// The frame's taper (GccOptions::taper_fraction, gcc_phat.h): a Tukey window whose first and
// last E = floor(taper_fraction n / 2) samples rise and fall as half cosines,
//   gain(i) = (1 - cos(pi (j + 1/2) / E)) / 2 for j = min(i, n - 1 - i) < E, else 1,
// so no sample is zeroed and the frame's middle is untouched (E = 0: a rectangle).
LOCALIZER_HOST_DEVICE inline int TaperEdgeSamples(int n, float taper_fraction) {
  return static_cast<int>(0.5f * taper_fraction * static_cast<float>(n));
}
LOCALIZER_HOST_DEVICE inline float TaperGain(int i, int n, int edge) {
  const int j = i < n - 1 - i ? i : n - 1 - i;
  if (j >= edge) return 1.0f;
  return 0.5f * (1.0f - cosf(3.14159265358979f * (static_cast<float>(j) + 0.5f) / static_cast<float>(edge)));
}

// X_k conj(X_r).
LOCALIZER_HOST_DEVICE inline CrossBin CrossOf(CrossBin xr, CrossBin xk) {
  return {xk.re * xr.re + xk.im * xr.im, xk.im * xr.re - xk.re * xr.im};
}

LOCALIZER_HOST_DEVICE inline float Magnitude(CrossBin c) { return sqrtf(c.re * c.re + c.im * c.im); }
LOCALIZER_HOST_DEVICE inline float PowerOf(CrossBin x) { return x.re * x.re + x.im * x.im; }

// 1e-12 of a power (sum of squared samples, or its geometric mean for a cross-spectrum) as a
// float within [FLT_MIN, FLT_MAX]: the floor that keeps silent bins finite.
LOCALIZER_HOST_DEVICE inline float PowerFloor(double power) {
  return static_cast<float>(
      hd::Clamp(kRelativeFloor * power, static_cast<double>(FLT_MIN), static_cast<double>(FLT_MAX)));
}

// The weights W of one bin whose cross product has magnitude `mag`.
// PHAT: 1 / max(|G|, floor).
LOCALIZER_HOST_DEVICE inline float PhatWeightOf(float mag, float floor_mag) { return 1.0f / hd::Max(mag, floor_mag); }
// PHAT-beta: max(|G|, floor)^-beta = exp(-beta ln max(|G|, floor)) with FastExp / FastLog.
LOCALIZER_HOST_DEVICE inline float PhatBetaWeightOf(float mag, float floor_mag, float beta) {
  return FastExp(-beta * FastLog(hd::Max(mag, floor_mag)));
}
// SCOT: 1 / sqrt(max(|X_r|^2, floor_r) max(|X_k|^2, floor_k)), as two square roots so that
// the product of two floors (each >= FLT_MIN) cannot underflow.
LOCALIZER_HOST_DEVICE inline float ScotWeightOf(float ref_power, float sensor_power, float floor_ref_power,
                                                float floor_sensor_power) {
  return 1.0f / (sqrtf(hd::Max(ref_power, floor_ref_power)) * sqrtf(hd::Max(sensor_power, floor_sensor_power)));
}

// Index of lag `lag` in a circular correlation of length n (negative lags wrap to the end).
LOCALIZER_HOST_DEVICE inline int WrapLag(int lag, int n) { return ((lag % n) + n) % n; }

// The main lobe around window index `peak` of a window r(0..size-1): the samples either side
// that stay positive and keep falling. r is any callable int -> float.
template <typename Window>
LOCALIZER_HOST_DEVICE inline void MainLobe(const Window& r, int size, int peak, int* first, int* last) {
  int f = peak;
  while (f > 0 && r(f - 1) > 0.0f && r(f - 1) <= r(f)) --f;
  int l = peak;
  while (l < size - 1 && r(l + 1) > 0.0f && r(l + 1) <= r(l)) ++l;
  *first = f;
  *last = l;
}

// The same rule on the full circular correlation (at: lag -> R, any integer lag), for a
// window that is all main lobe; returns the lobe's first and last lag (last - first < n).
// The sidelobe is then the largest |R| at lags last + 1 .. first + n - 1.
template <typename Circular>
LOCALIZER_HOST_DEVICE inline void CircularMainLobe(const Circular& at, int n, int peak_lag, int* first_lag,
                                                   int* last_lag) {
  int f = peak_lag;
  int l = peak_lag;
  while (l - f < n - 1 && at(f - 1) > 0.0f && at(f - 1) <= at(f)) --f;
  while (l - f < n - 1 && at(l + 1) > 0.0f && at(l + 1) <= at(l)) ++l;
  *first_lag = f;
  *last_lag = l;
}

// peak / sidelobe, capped at kQualityCap; the cap for a positive peak without sidelobe, 0 for
// none.
LOCALIZER_HOST_DEVICE inline float QualityRatio(float peak, float sidelobe) {
  if (!(sidelobe > 0.0f)) return peak > 0.0f ? kQualityCap : 0.0f;
  return hd::Min(peak / sidelobe, kQualityCap);
}

}  // namespace localizer::engine
