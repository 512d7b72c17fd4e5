// Per-particle maths of the GPU particle filter, as __host__ __device__ functions so the
// kernels (pf_kernels.cu) and host tests (tests/gpu/pf_math_test.cu) run the same code.
// Each function is the CPU engine's formula (engine/filters/particle_set.cc) for one
// particle; see engine/filters/particle_filter.h for the model.
//
// Plain C++ when not compiled by nvcc (the qualifiers vanish), so g++ tests can include it.
// No Eigen, no engine headers: every type is float/double arrays.
//
// Conventions: a particle's state is float s[6] = (x, y, z, vx, vy, vz), m and m/s,
// positions relative to the array centroid; a 6x6 matrix is double[36], row-major; a lower
// triangular 6x6 root packed by rows is float[21], element (r, c <= r) at r (r + 1) / 2 + c.
#pragma once

#include <math.h>

#if defined(__CUDACC__)
#define LOCALIZER_HD __host__ __device__ __forceinline__
#else
#define LOCALIZER_HD inline
#endif

namespace localizer::gpu::pf {

// ---- Predict ------------------------------------------------------------------------------

// Constant velocity with white acceleration a = accel_sigma * (ax, ay, az), (ax, ay, az) ~ N(0, I):
//   p <- p + v dt + a dt^2 / 2,  v <- v + a dt
// a_to_p = accel_sigma dt^2 / 2 and a_to_v = accel_sigma dt, computed in double by the caller
// and rounded to float, as ParticleSet::Predict does.
LOCALIZER_HD void PredictParticle(float s[6], float dt, float a_to_p, float a_to_v, float ax, float ay,
                                  float az) {
  s[0] += s[3] * dt + a_to_p * ax;
  s[1] += s[4] * dt + a_to_p * ay;
  s[2] += s[5] * dt + a_to_p * az;
  s[3] += a_to_v * ax;
  s[4] += a_to_v * ay;
  s[5] += a_to_v * az;
}

// ---- Measurement model --------------------------------------------------------------------

// Range r = |p - m| + 1e-6 (m; the epsilon keeps 1/r finite) and range rate vr = (p - m).v / r
// (m/s) of a particle from a sensor at m (relative to the centroid, like the particle).
struct RangeRate {
  float r;
  float vr;
};

LOCALIZER_HD RangeRate RangeAndRate(const float s[6], float mx, float my, float mz) {
  const float dx = s[0] - mx, dy = s[1] - my, dz = s[2] - mz;
  const float r = sqrtf(dx * dx + dy * dy + dz * dz) + 1e-6f;
  return {r, (dx * s[3] + dy * s[4] + dz * s[5]) / r};
}

// Predicted delay of pair (reference, k) at the instant the pair describes (d/2 before the
// frame centre, first order), seconds:
//   h' = (r_k - r_ref) / c - (d / 2) (vr_k - vr_ref) / c,   half_d = d / 2, inv_c = 1 / c.
LOCALIZER_HD float PairDelay(RangeRate sensor, RangeRate reference, float half_d, float inv_c) {
  return (sensor.r - reference.r) * inv_c - half_d * (sensor.vr - reference.vr) * inv_c;
}

// Peak likelihood: log of a Student-t density in e = (d - h') / sigma, up to a constant,
//   -(nu + 1) / 2 log(1 + e^2 / nu),   inv_dof = 1 / nu, half_dof_plus_1 = (nu + 1) / 2.
LOCALIZER_HD float StudentTLogLikelihood(float e, float inv_dof, float half_dof_plus_1) {
  return -half_dof_plus_1 * logf(1.0f + e * e * inv_dof);
}

// The fine-lag coordinate of delay h in a pair's upsampled GCC window:
//   lag = h * fs * upsampling - first_lag * upsampling   (lag_scale, lag0 from the caller).
LOCALIZER_HD float GccFineLag(float h, float lag_scale, float lag0) { return h * lag_scale - lag0; }

// Catmull-Rom read of the fine GCC g at fractional index `lag`, clamped to [1, last] where
// last = (fine length - 3) - 1e-3 (so g[i0 - 1 .. i0 + 2] exist). Smooth between lags, so
// no particle is favoured for sitting on one. The GCC log-likelihood is gain * this value.
// A NaN lag reads at 1 (the CPU's clamp would index out of bounds).
LOCALIZER_HD float CatmullRomRead(const float* g, float lag, float last) {
  lag = lag >= 1.0f ? lag : 1.0f;  // also maps NaN to 1
  lag = lag <= last ? lag : last;
  const int i0 = static_cast<int>(lag);
  const float t = lag - static_cast<float>(i0);
  const float gm = g[i0 - 1], g0 = g[i0], g1 = g[i0 + 1], g2 = g[i0 + 2];
  return g0 + 0.5f * t * ((g1 - gm) + t * ((2.0f * gm - 5.0f * g0 + 4.0f * g1 - g2) +
                                           t * (3.0f * (g0 - g1) + g2 - gm)));
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
LOCALIZER_HD int SystematicParent(const Cumulative& cum, int n, double u0, int m) {
  const double scale = static_cast<double>(n);
  const double target = static_cast<double>(m);
  int lo = 0, hi = n - 1;  // answer in [lo, hi]; every j < lo has n C_j - u0 <= m
  while (lo < hi) {
    const int mid = lo + (hi - lo) / 2;
    if (cum(mid) * scale - u0 <= target) lo = mid + 1;
    else hi = mid;
  }
  return lo;
}

// ---- Regularisation (Liu & West) ----------------------------------------------------------

// Silverman's bandwidth for d = 6 scaled by kernel_scale, capped at 0.95, and the shrinkage
// a = sqrt(1 - h^2) (ParticleSet::ResampleSystematic).
LOCALIZER_HD double KernelBandwidth(double kernel_scale, int n) {
  const double h = kernel_scale * pow(4.0 / (static_cast<double>(n) * 8.0), 0.1);
  return h < 0.95 ? h : 0.95;
}
LOCALIZER_HD double KernelShrinkage(double h) { return sqrt(1.0 - h * h); }

// x' = a x + shift + L z, shift = (1 - a) mean, L = h chol(cov) packed lower triangular,
// z with zero mean and unit covariance: keeps the weighted mean and covariance.
LOCALIZER_HD void LiuWestMove(const float x[6], float a, const float shift[6], const float root[21],
                              const float z[6], float out[6]) {
  int k = 0;
  for (int r = 0; r < 6; ++r) {
    float v = a * x[r] + shift[r];
    for (int c = 0; c <= r; ++c) v += root[k++] * z[c];
    out[r] = v;
  }
}

LOCALIZER_HD bool FiniteValue(double x) { return x - x == 0.0; }  // false for inf and NaN

// Lower-triangular L (double[36], row-major, zeros above the diagonal) with L L^T = a, from
// a's lower triangle. Returns true when a is numerically positive definite (every pivot
// above 1e-12 of the largest diagonal entry): then L is the Cholesky factor. Otherwise
// (a collapsed dimension: semi-definite, or slightly indefinite by rounding) each failing
// pivot's column is set to zero and the factorisation goes on, so L is finite and L L^T
// equals a up to about that tolerance in the collapsed directions — the kernel then adds
// no spread there, like the CPU's eigen-root fallback. Non-finite input gives L = 0, false.
// Cost: ~ 100 flops in double; run once per resampled session.
LOCALIZER_HD bool CholeskyLower6(const double a[36], double l[36]) {
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
LOCALIZER_HD void MomentTerms(const float s[6], const float shift[6], float w, T terms[kMomentSums]) {
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
LOCALIZER_HD void FinishMoments(const double sums[kMomentSums], const float shift[6], double mean[6],
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
