// Per-particle maths of the GPU particle filter, as __host__ __device__ functions so the
// kernels (pf_kernels.cu) and host tests (tests/gpu/pf_math_test.cu) run the same code.
// The formulas the CPU filter shares are the engine's own (engine/filters/particle_math.h:
// prediction, range and range rate, pair delay, the GCC read, the kernel's bandwidth and
// move), called here through adapters for the kernels' state arrays; what stays here is what
// the GPU does its own way: the Student-t log with CUDA's logf, systematic resampling by a
// per-slot search, the pivot-skipping Cholesky, and block-summed moments.
// See engine/filters/particle_filter.h for the model.
//
// Plain C++ when not compiled by nvcc (the qualifiers vanish, engine/core/host_device.h), so
// g++ tests can include it. No Eigen: every type is float/double arrays.
//
// Conventions: a particle's state is float s[6] = (x, y, z, vx, vy, vz), m and m/s,
// positions relative to the array centroid; a 6x6 matrix is double[36], row-major; a lower
// triangular 6x6 root packed by rows is float[21], element (r, c <= r) at r (r + 1) / 2 + c.
#pragma once

#include <math.h>

#include "engine/core/host_device.h"
#include "engine/filters/particle_math.h"

namespace localizer::gpu::pf {

// ---- Predict ------------------------------------------------------------------------------

// Constant velocity with white acceleration a = accel_sigma * (ax, ay, az), (ax, ay, az) ~ N(0, I):
//   p <- p + v dt + a dt^2 / 2,  v <- v + a dt   (engine::PredictAxis per axis)
// a_to_p = accel_sigma dt^2 / 2 and a_to_v = accel_sigma dt, computed in double by the caller
// and rounded to float, as ParticleSet::Predict does.
LOCALIZER_HOST_DEVICE_INLINE void PredictParticle(float s[6], float dt, float a_to_p, float a_to_v, float ax, float ay,
                                                  float az) {
  engine::PredictAxis(s[0], s[3], dt, a_to_p, a_to_v, ax);
  engine::PredictAxis(s[1], s[4], dt, a_to_p, a_to_v, ay);
  engine::PredictAxis(s[2], s[5], dt, a_to_p, a_to_v, az);
}

// ---- Measurement model --------------------------------------------------------------------

// Range r = |p - m| + 1e-6 and range rate vr = (p - m).v / r of a particle from a sensor at
// m (relative to the centroid, like the particle): engine::RangeAndRate.
using engine::RangeRate;
LOCALIZER_HOST_DEVICE_INLINE RangeRate RangeAndRate(const float s[6], float mx, float my, float mz) {
  return engine::RangeAndRate(s[0] - mx, s[1] - my, s[2] - mz, s[3], s[4], s[5]);
}

// Predicted delay of pair (reference, k): engine::PairDelay.
LOCALIZER_HOST_DEVICE_INLINE float PairDelay(RangeRate sensor, RangeRate reference, float half_d, float inv_c) {
  return engine::PairDelay(sensor.r, sensor.vr, reference.r, reference.vr, half_d, inv_c);
}

// Peak likelihood: log of a Student-t density in e = (d - h') / sigma, up to a constant,
//   -(nu + 1) / 2 log(1 + e^2 / nu),   inv_dof = 1 / nu, half_dof_plus_1 = (nu + 1) / 2.
// With CUDA's logf (the CPU uses engine::FastLog; ~1e-7 relative apart).
LOCALIZER_HOST_DEVICE_INLINE float StudentTLogLikelihood(float e, float inv_dof, float half_dof_plus_1) {
  return -half_dof_plus_1 * logf(1.0f + e * e * inv_dof);
}

// The GCC likelihood's read (engine::GccFineLag, engine::CatmullRomRead) is the engine's.

// ---- Initialisation -----------------------------------------------------------------------

// A Gaussian belief's particle: x = mean + root z, root row-major 6x6, z ~ N(0, I6) (the
// first six Philox normals of the slot's draw window). Summed over k in order, as the
// one-slot and the batched initialisation kernels both do.
LOCALIZER_HOST_DEVICE_INLINE void GaussianParticle(const float mean[6], const float root[36], const float z[6],
                                                   float x[6]) {
  for (int r = 0; r < 6; ++r) {
    float v = mean[r];
    for (int k = 0; k < 6; ++k) v += root[r * 6 + k] * z[k];
    x[r] = v;
  }
}

// A region's particle: position lo + span u (u in (0, 1], curand's uniforms), velocity
// speed_sigma v (v ~ N(0, I3)).
LOCALIZER_HOST_DEVICE_INLINE void RegionParticle(const float lo[3], const float span[3], float speed_sigma,
                                                 const float u[3], const float v[3], float x[6]) {
  for (int a = 0; a < 3; ++a) {
    x[a] = lo[a] + span[a] * u[a];
    x[3 + a] = speed_sigma * v[a];
  }
}

// ---- Systematic resampling ----------------------------------------------------------------

// The particle that output slot m (0 <= m < n) copies under systematic resampling with
// offset u0 in [0, 1), given the inclusive cumulative normalised weights C_0 .. C_{n-1}
// read through cum(j). Particle j owns slots [k_{j-1}, k_j) with k_j = ceil(n C_j - u0), so
// slot m goes to the first j with n C_j - u0 > m; the last particle takes what rounding
// leaves over. Equals ParticleSet::SystematicIndices' mark-and-running-max for the same C
// and u0 (tests/gpu/pf_math_test.cu). Zero-weight particles (flat C) own no slot.
// Cost: log2(n) reads of C. Each slot searches on its own: no sequential pass.
template <typename Cumulative>
LOCALIZER_HOST_DEVICE_INLINE int SystematicParent(const Cumulative& cum, int n, double u0, int m) {
  const double scale = static_cast<double>(n);
  const double target = static_cast<double>(m);
  int lo = 0, hi = n - 1;  // answer in [lo, hi]; every j < lo has n C_j - u0 <= m
  while (lo < hi) {
    const int mid = lo + (hi - lo) / 2;
    if (cum(mid) * scale - u0 <= target)
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo;
}

// ---- Regularisation (Liu & West) ----------------------------------------------------------

// The bandwidth and shrinkage are engine::KernelBandwidth and engine::KernelShrinkage.

// x' = a x + shift + L z, shift = (1 - a) mean, L = h chol(cov) packed lower triangular,
// z with zero mean and unit covariance: keeps the weighted mean and covariance
// (engine::LiuWestRow per row; row r's coefficients start at r (r + 1) / 2).
struct UnitDraws {  // z(c) for engine::LiuWestRow
  const float* z;
  LOCALIZER_HOST_DEVICE float operator()(int c) const { return z[c]; }
};
LOCALIZER_HOST_DEVICE_INLINE void LiuWestMove(const float x[6], float a, const float shift[6], const float root[21],
                                              const float z[6], float out[6]) {
  for (int r = 0; r < 6; ++r) out[r] = engine::LiuWestRow(a, x[r], shift[r], root + r * (r + 1) / 2, r, UnitDraws{z});
}

LOCALIZER_HOST_DEVICE_INLINE bool FiniteValue(double x) { return x - x == 0.0; }  // false for inf and NaN

// Lower-triangular L (double[36], row-major, zeros above the diagonal) with L L^T = a, from
// a's lower triangle. Returns true when a is numerically positive definite (every pivot
// above 1e-12 of the largest diagonal entry): then L is the Cholesky factor. Otherwise
// (a collapsed dimension: semi-definite, or slightly indefinite by rounding) each failing
// pivot's column is set to zero and the factorisation goes on, so L is finite and L L^T
// equals a up to about that tolerance in the collapsed directions — the kernel then adds
// no spread there, like the CPU's eigen-root fallback. Non-finite input gives L = 0, false.
// Cost: ~ 100 flops in double; run once per resampled session.
LOCALIZER_HOST_DEVICE_INLINE bool CholeskyLower6(const double a[36], double l[36]) {
  bool finite = true;
  double max_diag = 0.0;
  for (int i = 0; i < 36; ++i) {
    l[i] = 0.0;
    finite = finite && FiniteValue(a[i]);
  }
  if (!finite) return false;
  for (int i = 0; i < 6; ++i) max_diag = fmax(max_diag, fabs(a[i * 7]));
  const double tol = 1e-12 * max_diag;
  bool definite = true;
  for (int j = 0; j < 6; ++j) {
    double d = a[j * 6 + j];
    for (int k = 0; k < j; ++k) d -= l[j * 6 + k] * l[j * 6 + k];
    if (!(d > tol)) {  // collapsed direction: no spread along this column
      definite = false;
      continue;
    }
    const double ljj = sqrt(d);
    l[j * 6 + j] = ljj;
    for (int i = j + 1; i < 6; ++i) {
      double s = a[i * 6 + j];
      for (int k = 0; k < j; ++k) s -= l[i * 6 + k] * l[j * 6 + k];
      l[i * 6 + j] = s / ljj;
    }
  }
  return definite;
}

// ---- Weighted moments ---------------------------------------------------------------------

// Sums accumulated per particle for the weighted mean and covariance, about a shift point
// near the cloud (particle 0's state) so float sums of squares do not cancel:
//   sums[0] = sum w,  sums[1 + r] = sum w d_r,  sums[7 + k] = sum w d_r d_c  (r <= c, k in
//   row order over the upper triangle), d = x - shift.
inline constexpr int kMomentSums = 28;

template <typename T>
LOCALIZER_HOST_DEVICE_INLINE void MomentTerms(const float s[6], const float shift[6], float w, T terms[kMomentSums]) {
  float d[6];
  for (int r = 0; r < 6; ++r) d[r] = s[r] - shift[r];
  terms[0] = w;
  int k = 7;
  for (int r = 0; r < 6; ++r) {
    const float wd = w * d[r];
    terms[1 + r] = wd;
    for (int c = r; c < 6; ++c) terms[k++] = wd * d[c];
  }
}

// mean = shift + S1 / S0, cov = S2 / S0 - (S1 / S0)(S1 / S0)^T (symmetric, double[36]).
// S0 <= 0 (no weight) gives mean = shift and cov = 0.
LOCALIZER_HOST_DEVICE_INLINE void FinishMoments(const double sums[kMomentSums], const float shift[6], double mean[6],
                                                double cov[36]) {
  const double inv_w = sums[0] > 0.0 ? 1.0 / sums[0] : 0.0;
  double m[6];
  for (int r = 0; r < 6; ++r) {
    m[r] = sums[1 + r] * inv_w;
    mean[r] = static_cast<double>(shift[r]) + m[r];
  }
  int k = 7;
  for (int r = 0; r < 6; ++r) {
    for (int c = r; c < 6; ++c) {
      const double v = sums[k++] * inv_w - m[r] * m[c];
      cov[r * 6 + c] = v;
      cov[c * 6 + r] = v;
    }
  }
}

}  // namespace localizer::gpu::pf
