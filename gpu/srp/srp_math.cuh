// The maths of the batched SRP-PHAT (srp_batch.h), callable on the host and on the device: the
// kernels (srp_kernels.cu) inline these functions, and tests/gpu/srp_math_test.cu runs the same
// code on the host against engine/doa's CPU SrpPhat on the same pair spectra.
//
// Notation (engine/doa/pair_spectra.h): for pair p = (i, j), i < j, in the order (0,1), (0,2),
// ..., (1,2), ..., the PHAT-weighted cross-spectrum G_p(k) = X_i conj(X_j) / |X_i conj(X_j)| over
// the B consecutive in-band bins k = first_bin .. first_bin + B - 1 of a transform of M points.
// A far-field direction u gives pair p the lag D_p.u samples (srp_phat.h: D_p = -(m_i - m_j)
// fs / c), and the steered response power there is
//     power(u) = sum_p sum_k Re(G_p(k) exp(i w_k D_p.u)),     w_k = 2 pi k / M,
// which is B sqrt(P) sigma times the CPU's statistic z(u) (SrpPhat::Statistic; sigma =
// PairSpectra::noise_sigma()). The map is evaluated in float, the refinement in double.
//
// Float accuracy of the map (tests/gpu/srp_math_test.cu): each pair's bins are summed along a
// phasor chain (one sincos per pair and direction, then one complex product per bin) that is
// re-anchored with a fresh sincos every kAnchorBins bins, so the rounding of the rotation does
// not grow with B; measured against the double CPU on plane-wave frames, |z_float - z_cpu|
// stays below kSrpMapToleranceZ (srp_batch.h states it).
//
// Plain C++ without nvcc (engine/core/host_device.h): the qualifiers vanish.
#pragma once

#include <cmath>
#include <cstdint>

#include "engine/core/host_device.h"

namespace localizer::gpu::srp {

// What the array can observe (engine::ArrayShape, engine/doa/array_shape.h), as the refinement
// needs it: the parametrisation it moves in.
enum ShapeCode : int32_t { kVolumetric = 0, kPlanar = 1, kLinear = 2 };

// A phasor chain is restarted from an exact sincos after this many bins (of its own stride).
// 32 products in float keep the chain's drift near 32 x 6e-8 relative; one sincos per 32 bins
// costs ~5 % of the map's arithmetic.
constexpr int kAnchorBins = 32;

// The band an array's spectra cover: bins first_bin .. first_bin + bins - 1 of an M-point
// transform (w_k = radians_per_bin_lag k per sample of lag, radians_per_bin_lag = 2 pi / M).
struct SrpBand {
  int32_t first_bin = 0;
  int32_t bins = 0;
  double radians_per_bin_lag = 0.0;
};

// sin and cos of one argument, in the argument's precision.
LOCALIZER_HOST_DEVICE_INLINE void SinCos(float x, float* s, float* c) {
#if defined(__CUDA_ARCH__)
  sincosf(x, s, c);
#else
  *s = sinf(x);
  *c = cosf(x);
#endif
}
LOCALIZER_HOST_DEVICE_INLINE void SinCos(double x, double* s, double* c) {
#if defined(__CUDA_ARCH__)
  sincos(x, s, c);
#else
  *s = sin(x);
  *c = cos(x);
#endif
}

// sum over the bins b = lane, lane + lanes, ... < band.bins of Re(G(b) exp(i w_b lag)), in T.
// g: one pair's spectrum, (re, im) interleaved floats, band.bins of them. lanes = 1 sums every
// bin; the kernels' warps split a pair's bins over their lanes and add the lanes' sums.
template <typename T>
LOCALIZER_HOST_DEVICE_INLINE T SteeredPairSum(const float* g, const SrpBand& band, T lag_samples, int lane,
                                              int lanes) {
  const T per_bin = static_cast<T>(band.radians_per_bin_lag) * lag_samples;  // radians per bin
  T step_s, step_c;
  SinCos(per_bin * static_cast<T>(lanes), &step_s, &step_c);
  T sum = 0;
  for (int start = lane; start < band.bins; start += kAnchorBins * lanes) {
    T pr, pi;  // exp(i w_b lag) at the chain's first bin, exact
    SinCos(per_bin * static_cast<T>(band.first_bin + start), &pi, &pr);
    const int end = start + kAnchorBins * lanes < band.bins ? start + kAnchorBins * lanes : band.bins;
    for (int b = start; b < end; b += lanes) {
      const T gr = static_cast<T>(g[2 * b]), gi = static_cast<T>(g[2 * b + 1]);
      sum += gr * pr - gi * pi;
      const T next_r = pr * step_c - pi * step_s;
      pi = pr * step_s + pi * step_c;
      pr = next_r;
    }
  }
  return sum;
}

// power(u) over every pair (lanes = 1) from one session's spectra: pair p's band.bins complex
// values start at spectra + 2 p band.bins; lag_per_direction holds D_p (3 floats per pair).
template <typename T>
LOCALIZER_HOST_DEVICE_INLINE T SteeredPower(const float* spectra, const float* lag_per_direction, int pairs,
                                            const SrpBand& band, T ux, T uy, T uz) {
  T power = 0;
  for (int p = 0; p < pairs; ++p) {
    const float* d = lag_per_direction + 3 * p;
    const T lag = static_cast<T>(d[0]) * ux + static_cast<T>(d[1]) * uy + static_cast<T>(d[2]) * uz;
    power += SteeredPairSum<T>(spectra + 2 * static_cast<int64_t>(p) * band.bins, band, lag, 0, 1);
  }
  return power;
}

// ---- Refinement: the CPU's Newton's method (engine/doa/direction_search.cc, SrpPhat::Refine) ----

// sum over a pair's bins (lane-strided as SteeredPairSum) of Re(G exp(i w lag)) and its first
// two derivatives in lag: the CPU's PairSpectra::At times B (At divides by B).
struct LagSums {
  double r = 0.0, dr = 0.0, d2r = 0.0;
};

LOCALIZER_HOST_DEVICE_INLINE LagSums PairLagSums(const float* g, const SrpBand& band, double lag_samples, int lane,
                                                 int lanes) {
  const double per_bin = band.radians_per_bin_lag * lag_samples;
  double step_s, step_c;
  SinCos(per_bin * lanes, &step_s, &step_c);
  double pr, pi;
  SinCos(per_bin * (band.first_bin + lane), &pi, &pr);
  LagSums out;
  for (int b = lane; b < band.bins; b += lanes) {  // double: the chain's drift stays ~1e-14
    const double w = band.radians_per_bin_lag * (band.first_bin + b);
    const double gr = g[2 * b], gi = g[2 * b + 1];
    const double tr = gr * pr - gi * pi, ti = gr * pi + gi * pr;
    out.r += tr;
    out.dr -= w * ti;
    out.d2r -= w * w * tr;
    const double next_r = pr * step_c - pi * step_s;
    pi = pr * step_s + pi * step_c;
    pr = next_r;
  }
  return out;
}

struct Dir3 {
  double x = 0.0, y = 0.0, z = 0.0;
};
LOCALIZER_HOST_DEVICE_INLINE double Dot(const Dir3& a, const Dir3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
LOCALIZER_HOST_DEVICE_INLINE Dir3 Cross(const Dir3& a, const Dir3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
LOCALIZER_HOST_DEVICE_INLINE Dir3 Scaled(const Dir3& a, double s) { return {a.x * s, a.y * s, a.z * s}; }
LOCALIZER_HOST_DEVICE_INLINE Dir3 Plus(const Dir3& a, const Dir3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
LOCALIZER_HOST_DEVICE_INLINE Dir3 Normalised(const Dir3& a) { return Scaled(a, 1.0 / sqrt(Dot(a, a))); }

// One array's fixed description for the refinement.
struct RefineGeometry {
  int32_t shape = kVolumetric;
  int32_t pairs = 0;
  Dir3 axis;                  // linear: the line; planar: the normal (engine::ArrayShapeInfo::axis)
  double max_step_rad = 0.0;  // the CPU's 2 x leaf radius = 1 / max_p g_p
  double inv_bins = 0.0;      // 1 / B: the CPU's R_p is the bins' mean
  const double* lag_per_direction = nullptr;  // D_p, 3 doubles per pair
};

// A direction as the refinement moves it: u on the sphere (or the plane's side of it), or the
// cone angle theta for linear arrays (u is then unused).
struct RefineCell {
  Dir3 u;
  double theta_rad = 0.0;
};

// The refinement's start at a grid direction as the grid is stored (3 floats): u, and its cone
// angle to the axis (linear arrays; meaningless but harmless for the others).
LOCALIZER_HOST_DEVICE_INLINE RefineCell StartCell(const float* grid_u, const Dir3& axis) {
  RefineCell cell;
  cell.u = {grid_u[0], grid_u[1], grid_u[2]};
  cell.theta_rad = acos(engine::hd::Clamp(Dot(cell.u, axis), -1.0, 1.0));
  return cell;
}

struct RefineProbe {
  double value = 0.0;                   // sum_p R_p at the cell
  double g0 = 0.0, g1 = 0.0;            // gradient in the step's axes
  double h00 = 0.0, h01 = 0.0, h11 = 0.0;  // Hessian
  Dir3 b0, b1;                          // the step's axes (sphere and plane)
};

// sum_p R_p with gradient and Hessian at `cell` (SrpPhat::ProbeAt). pair_sums(p, lag) returns
// LagSums over ALL of pair p's bins (a device caller reduces its lanes inside it, so that every
// lane sees the same sums and takes the same branches).
template <class PairSums>
LOCALIZER_HOST_DEVICE_INLINE RefineProbe ProbeAt(const RefineGeometry& geo, const RefineCell& cell,
                                                 PairSums& pair_sums) {
  RefineProbe out;
  if (geo.shape == kLinear) {
    const double c = cos(cell.theta_rad), s = sin(cell.theta_rad);
    for (int p = 0; p < geo.pairs; ++p) {
      const double* d = geo.lag_per_direction + 3 * p;
      const double a = d[0] * geo.axis.x + d[1] * geo.axis.y + d[2] * geo.axis.z;
      const LagSums v = pair_sums(p, a * c);
      const double r = v.r * geo.inv_bins, dr = v.dr * geo.inv_bins, d2r = v.d2r * geo.inv_bins;
      out.value += r;
      out.g0 += dr * (-a * s);
      out.h00 += d2r * a * a * s * s + dr * (-a * c);
    }
    out.h11 = -1.0;  // the unused axis: keeps the matrix definite
    return out;
  }
  const bool planar = geo.shape == kPlanar;
  const Dir3 normal = planar ? geo.axis : cell.u;
  const Dir3 other = fabs(normal.x) < 0.9 ? Dir3{1.0, 0.0, 0.0} : Dir3{0.0, 1.0, 0.0};
  out.b0 = Normalised(Cross(normal, other));
  out.b1 = Cross(normal, out.b0);
  double radial = 0.0;  // the sphere's curvature: u(v) = (u + E v) / |u + E v|
  for (int p = 0; p < geo.pairs; ++p) {
    const double* dp = geo.lag_per_direction + 3 * p;
    const Dir3 d{dp[0], dp[1], dp[2]};
    const double lag = Dot(d, cell.u);
    const LagSums v = pair_sums(p, lag);
    const double r = v.r * geo.inv_bins, dr = v.dr * geo.inv_bins, d2r = v.d2r * geo.inv_bins;
    const double a0 = Dot(out.b0, d), a1 = Dot(out.b1, d);
    out.value += r;
    out.g0 += dr * a0;
    out.g1 += dr * a1;
    out.h00 += d2r * a0 * a0;
    out.h01 += d2r * a0 * a1;
    out.h11 += d2r * a1 * a1;
    radial += dr * lag;
  }
  if (!planar) {
    out.h00 -= radial;
    out.h11 -= radial;
  }
  return out;
}

// The cell a step (in the probe's axes) leads to (SrpPhat::Moved).
LOCALIZER_HOST_DEVICE_INLINE RefineCell Moved(const RefineGeometry& geo, const RefineCell& cell,
                                              const RefineProbe& probe, double s0, double s1) {
  RefineCell next = cell;
  if (geo.shape == kLinear) {
    next.theta_rad = engine::hd::Clamp(cell.theta_rad + s0, 0.0, 3.14159265358979323846);
  } else if (geo.shape == kPlanar) {
    const Dir3& n = geo.axis;
    Dir3 w = Plus(Plus(cell.u, Scaled(n, -Dot(cell.u, n))), Plus(Scaled(probe.b0, s0), Scaled(probe.b1, s1)));
    const double w2 = Dot(w, w);
    if (sqrt(w2) > 1.0) w = Normalised(w);
    next.u = Plus(w, Scaled(n, sqrt(engine::hd::Max(0.0, 1.0 - Dot(w, w)))));
  } else {
    next.u = Normalised(Plus(cell.u, Plus(Scaled(probe.b0, s0), Scaled(probe.b1, s1))));
  }
  return next;
}

struct RefineResult {
  RefineCell cell;
  double value = 0.0;  // sum_p R_p there; z = value / (sigma sqrt(P))
  int32_t iterations = 0;
  int32_t probes = 0;
};

// Newton's method from `cell` as SrpPhat::Refine takes it: at most kRefineIterations steps,
// each the Newton step where the Hessian is negative definite (else a quarter of the largest
// step along the gradient), capped at max_step_rad, halved up to kRefineHalvings times until
// the value rises; stops when no halving rises or the step falls below kRefineConverged_rad.
constexpr int kRefineIterations = 8;
constexpr int kRefineHalvings = 3;
constexpr double kRefineConverged_rad = 1e-5;

template <class PairSums>
LOCALIZER_HOST_DEVICE_INLINE RefineResult RefineDirection(const RefineGeometry& geo, RefineCell cell,
                                                          PairSums& pair_sums) {
  RefineResult out;
  RefineProbe probe = ProbeAt(geo, cell, pair_sums);
  out.probes = 1;
  for (int iteration = 0; iteration < kRefineIterations; ++iteration) {
    out.iterations = iteration + 1;
    // Largest eigenvalue of the symmetric 2 x 2 Hessian.
    const double mean = 0.5 * (probe.h00 + probe.h11), half_gap = 0.5 * (probe.h00 - probe.h11);
    const double largest = mean + sqrt(half_gap * half_gap + probe.h01 * probe.h01);
    double s0 = 0.0, s1 = 0.0;
    if (largest < 0.0) {  // -H^-1 g
      const double det = probe.h00 * probe.h11 - probe.h01 * probe.h01;
      s0 = -(probe.h11 * probe.g0 - probe.h01 * probe.g1) / det;
      s1 = -(-probe.h01 * probe.g0 + probe.h00 * probe.g1) / det;
    } else {
      const double g = sqrt(probe.g0 * probe.g0 + probe.g1 * probe.g1);
      if (g > 0.0) {
        s0 = 0.25 * geo.max_step_rad * probe.g0 / g;
        s1 = 0.25 * geo.max_step_rad * probe.g1 / g;
      }
    }
    const double norm = sqrt(s0 * s0 + s1 * s1);
    if (norm > geo.max_step_rad) {
      s0 *= geo.max_step_rad / norm;
      s1 *= geo.max_step_rad / norm;
    }
    bool improved = false;
    // As the CPU's loop: the step is halved after every try, the successful one included.
    for (int h = 0; h < kRefineHalvings && !improved; ++h, s0 *= 0.5, s1 *= 0.5) {
      const RefineCell next = Moved(geo, cell, probe, s0, s1);
      const RefineProbe there = ProbeAt(geo, next, pair_sums);
      ++out.probes;
      if (there.value > probe.value) {
        cell = next;
        probe = there;
        improved = true;
      }
    }
    if (!improved || sqrt(s0 * s0 + s1 * s1) < kRefineConverged_rad) break;
  }
  out.cell = cell;
  out.value = probe.value;
  return out;
}

// The arg-max's partial result: the larger value wins, the smaller index on ties (the first
// maximum, as std::max_element finds it), and NaN loses to any number, so the order is total
// and the winner does not depend on the order partial results are combined in. A map of NaN
// alone leaves NoMapPeak's index (past any grid).
struct MapPeak {
  float value;
  int32_t index;
};
LOCALIZER_HOST_DEVICE_INLINE MapPeak NoMapPeak() { return {-3.402823466e38f, 0x7fffffff}; }
LOCALIZER_HOST_DEVICE_INLINE MapPeak BetterMapPeak(MapPeak a, MapPeak b) {
  const bool a_nan = a.value != a.value, b_nan = b.value != b.value;  // isnan on both sides
  if (a_nan != b_nan) return a_nan ? b : a;
  if (!a_nan) {
    if (a.value > b.value) return a;
    if (b.value > a.value) return b;
  }
  return a.index <= b.index ? a : b;
}

}  // namespace localizer::gpu::srp
