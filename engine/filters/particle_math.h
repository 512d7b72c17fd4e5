// The particle filter's per-particle formulas, written once for the CPU's vectorised loops
// over structure-of-arrays columns (particle_set.cc, particle_motion.cc, particle_resampling.cc) and the GPU's
// kernels (gpu/filters/pf_kernels.cu, through the state-array adapters of pf_math.cuh):
// host_device.h. Each is the model of particle_filter.h for one particle, in float, in the
// order of operations the results depend on. Positions are relative to the array centroid.
//
// What the two sides do differently stays with each (and is not here): random numbers (the
// CPU's counter hash, the GPU's Philox), the log in the Student-t likelihood (the CPU's
// FastLog, CUDA's logf), systematic resampling (the CPU's sequential mark-and-max, the GPU's
// per-slot binary search: tests/gpu checks they pick the same parents), the kernel's root
// (Eigen's LLT with an eigen fallback, the GPU's pivot-skipping Cholesky) and the weighted
// moments (float sums on the CPU, double block sums on the GPU).
#pragma once

#include <cmath>

#include "engine/core/host_device.h"

namespace localizer::engine {

// Constant velocity with white acceleration a (one axis): p <- p + v dt + a_to_p a,
// v <- v + a_to_v a, with a_to_p = sigma_a dt^2 / 2 and a_to_v = sigma_a dt computed in
// double by the caller and rounded to float, a ~ N(0, 1).
LOCALIZER_HOST_DEVICE_INLINE void PredictAxis(float& p, float& v, float dt, float a_to_p, float a_to_v, float a) {
  p += v * dt + a_to_p * a;
  v += a_to_v * a;
}

// The same with the velocity mean-reverting (ParticleFilterOptions::velocity_time_constant_s):
// p <- p + v reach + a_to_p a, v <- d v + a_to_v a, with d = exp(-dt / tau) and reach =
// tau (1 - d). The CPU filter only, so far.
LOCALIZER_HOST_DEVICE_INLINE void PredictAxisReverting(float& p, float& v, float reach, float d, float a_to_p,
                                                       float a_to_v, float a) {
  p += v * reach + a_to_p * a;
  v = d * v + a_to_v * a;
}

// Motion blur (ParticleFilterOptions::motion_blur): the variance a pair's peak takes per
// (s/s)^2 of a particle's delay rate, s^2. A delay moving at rate r within a frame spreads the
// PHAT peak into a bell of variance b^2 = r^2 V (V = Measurement::window_time_var_s2), height
// A = peak_snr noise sds, whose top is flat beside the noise's ripples: the highest point lies
// about uniformly where the bell is within the largest ripple (about 2.5 sds) of its top,
// x^2 < 5 b^2 / peak_snr, a variance of 5/3 b^2 / peak_snr, i.e. kMotionBlurSnr / peak_snr of
// r^2 V, and all of it once the bell is no higher than that. `share`: the option (0: off);
// V <= 0 (a front end that does not state it): off.
inline constexpr double kMotionBlurSnr = 2.0;
inline double MotionBlurVariance(double share, double window_time_var_s2, double peak_snr) {
  if (!(share > 0.0) || !(window_time_var_s2 > 0.0) || !std::isfinite(window_time_var_s2)) return 0.0;
  const double of_bell = peak_snr > kMotionBlurSnr ? kMotionBlurSnr / peak_snr : 1.0;
  return share * of_bell * window_time_var_s2;
}

// Range r = |d| + 1e-6 (m; the epsilon keeps 1/r finite) and range rate vr = d.v / r (m/s)
// of a particle at offset d = p - m from a sensor m, moving at v.
struct RangeRate {
  float r;
  float vr;
};
LOCALIZER_HOST_DEVICE_INLINE RangeRate RangeAndRate(float dx, float dy, float dz, float vx, float vy, float vz) {
  const float r = sqrtf(dx * dx + dy * dy + dz * dz) + 1e-6f;
  return {r, (dx * vx + dy * vy + dz * vz) / r};
}

// Predicted delay of pair (reference, k) at the instant the pair describes (d/2 before the
// frame centre, first order), seconds:
//   h' = (r_k - r_ref) / c - (d / 2) (vr_k - vr_ref) / c,   half_d = d / 2, inv_c = 1 / c.
// (Scalars, not two RangeRates: passed by value inside the CPU's `omp simd` loop, the structs
// cost that loop its vector form.)
LOCALIZER_HOST_DEVICE_INLINE float PairDelay(float r_k, float vr_k, float r_ref, float vr_ref, float half_d,
                                             float inv_c) {
  return (r_k - r_ref) * inv_c - half_d * (vr_k - vr_ref) * inv_c;
}

// The fine-lag coordinate of delay h in a pair's upsampled GCC window:
//   lag = h fs upsampling - first_lag upsampling   (lag_scale, lag0 from the caller).
LOCALIZER_HOST_DEVICE_INLINE float GccFineLag(float h, float lag_scale, float lag0) { return h * lag_scale - lag0; }

// Catmull-Rom read of the fine GCC g at fractional index `lag`, clamped to [1, last] where
// last = (fine length - 3) - 1e-3 (so g[i0 - 1 .. i0 + 2] exist). Smooth between lags, so
// no particle is favoured for sitting on one. The GCC log-likelihood is gain * this value.
// A NaN lag reads at 1.
LOCALIZER_HOST_DEVICE_INLINE float CatmullRomRead(const float* g, float lag, float last) {
  lag = lag >= 1.0f ? lag : 1.0f;  // also maps NaN to 1
  lag = lag <= last ? lag : last;
  const int i0 = static_cast<int>(lag);
  const float t = lag - static_cast<float>(i0);
  const float gm = g[i0 - 1], g0 = g[i0], g1 = g[i0 + 1], g2 = g[i0 + 2];
  return g0 +
         0.5f * t * ((g1 - gm) + t * ((2.0f * gm - 5.0f * g0 + 4.0f * g1 - g2) + t * (3.0f * (g0 - g1) + g2 - gm)));
}

// The regularisation kernel's bandwidth h = kernel_scale (4 / (N (d + 2)))^(1 / (d + 4)),
// d = 6 (Silverman's optimum for a Gaussian), at most 0.95; and the Liu & West shrinkage
// a = sqrt(1 - h^2) that keeps the weighted covariance.
LOCALIZER_HOST_DEVICE inline double KernelBandwidth(double kernel_scale, int n) {
  const double d = 6.0;
  const double h = kernel_scale * pow(4.0 / (n * (d + 2.0)), 1.0 / (d + 4.0));
  return h < 0.95 ? h : 0.95;  // std::min(0.95, h)
}
LOCALIZER_HOST_DEVICE inline double KernelShrinkage(double h) { return sqrt(1.0 - h * h); }

// Row `row` of the kernel move x' = a x + shift + L z (Liu & West), L lower triangular:
//   x'_row = a x_row + shift_row + sum_{c <= row} root_row[c] z(c),
// added in that order; root_row holds L(row, 0..row) contiguously, z is any callable
// int -> float giving the particle's unit-variance draws.
template <typename Z>
LOCALIZER_HOST_DEVICE_INLINE float LiuWestRow(float a, float x, float shift, const float* root_row, int row,
                                              const Z& z) {
  float v = a * x + shift;
  for (int c = 0; c <= row; ++c) v += root_row[c] * z(c);
  return v;
}

}  // namespace localizer::engine
