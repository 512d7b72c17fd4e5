// Sub-sample refinement of a correlation peak, written once for the CPU stage and the GPU's
// peak kernel (host_device.h): the methods, their maths and their measured errors are in
// peak_interpolation.h; this header holds the arithmetic both sides run.
//
// samples[m] = R(peak + m - K), m = 0..2K, K = kPeakHalfWidth; InterpolatePeak returns the
// offset of the refined maximum from the centre sample, in samples, within [-1, 1].
#pragma once

#include <cmath>

#include "engine/core/host_device.h"

namespace localizer::engine {

enum class PeakInterpolation { kParabolic, kGaussian, kSinc };

// Samples either side of the peak that InterpolatePeak reads.
inline constexpr int kPeakHalfWidth = 8;
inline constexpr int kPeakSamples = 2 * kPeakHalfWidth + 1;

// The three-point fits (y_minus = R(peak - 1), y0 = R(peak), y_plus = R(peak + 1)).
LOCALIZER_HOST_DEVICE inline double ParabolicPeakOffset(double y_minus, double y0, double y_plus) {
  const double curvature = y_minus - 2.0 * y0 + y_plus;
  if (!(curvature < 0.0)) return 0.0;  // flat or not a maximum: no sub-sample information
  return hd::Clamp(0.5 * (y_minus - y_plus) / curvature, -1.0, 1.0);
}

LOCALIZER_HOST_DEVICE inline double GaussianPeakOffset(double y_minus, double y0, double y_plus) {
  if (!(y_minus > 0.0 && y0 > 0.0 && y_plus > 0.0)) return ParabolicPeakOffset(y_minus, y0, y_plus);
  return ParabolicPeakOffset(log(y_minus), log(y0), log(y_plus));
}

// cos and sin of pi j / K for tap j = m - K, m = 0..2K: the window's phase at each tap, so
// that a kernel evaluation needs one sin/cos pair instead of one per tap. The values are
// libm's cos and sin of the double angle pi * (m - K) / K (so cos(pi / 2) is 6.1e-17, not 0),
// which the CPU stage computed at start-up before they were written here; tests/tdoa checks
// that they still are.
LOCALIZER_HOST_DEVICE inline double CosTap(int m) {
  constexpr double kTable[kPeakSamples] = {-0x1p+0,
                                           -0x1.d906bcf328d46p-1,
                                           -0x1.6a09e667f3bccp-1,
                                           -0x1.87de2a6aea962p-2,
                                           0x1.1a62633145c07p-54,
                                           0x1.87de2a6aea964p-2,
                                           0x1.6a09e667f3bcdp-1,
                                           0x1.d906bcf328d46p-1,
                                           0x1p+0,
                                           0x1.d906bcf328d46p-1,
                                           0x1.6a09e667f3bcdp-1,
                                           0x1.87de2a6aea964p-2,
                                           0x1.1a62633145c07p-54,
                                           -0x1.87de2a6aea962p-2,
                                           -0x1.6a09e667f3bccp-1,
                                           -0x1.d906bcf328d46p-1,
                                           -0x1p+0};
  return kTable[m];
}
LOCALIZER_HOST_DEVICE inline double SinTap(int m) {
  constexpr double kTable[kPeakSamples] = {-0x1.1a62633145c07p-53,
                                           -0x1.87de2a6aea965p-2,
                                           -0x1.6a09e667f3bcdp-1,
                                           -0x1.d906bcf328d46p-1,
                                           -0x1p+0,
                                           -0x1.d906bcf328d46p-1,
                                           -0x1.6a09e667f3bccp-1,
                                           -0x1.87de2a6aea963p-2,
                                           0x0p+0,
                                           0x1.87de2a6aea963p-2,
                                           0x1.6a09e667f3bccp-1,
                                           0x1.d906bcf328d46p-1,
                                           0x1p+0,
                                           0x1.d906bcf328d46p-1,
                                           0x1.6a09e667f3bcdp-1,
                                           0x1.87de2a6aea965p-2,
                                           0x1.1a62633145c07p-53};
  return kTable[m];
}

// The reconstruction and its first two derivatives at x (offset from the centre sample).
struct SincValue {
  double value = 0.0;
  double slope = 0.0;
  double curvature = 0.0;
};

// The Hann-windowed sinc reconstruction sum_m samples[m] k(x - (m - K)) and its first two
// derivatives at x, |x| <= 1. With u = x - j for tap j: sin(pi u) = (-1)^j sin(pi x),
// cos(pi u) = (-1)^j cos(pi x), and the window's cos/sin(pi u / K) follow from the angle
// difference with the tap table, so one evaluation needs one sin/cos pair whatever the
// number of taps.
//   sinc'  = (cos(pi u) - sinc) / u          sinc'' = -pi^2 sinc - 2 sinc' / u
//   hann   = (1 + cos(pi u / K)) / 2         hann'  = -(pi / 2K) sin(pi u / K)
//   hann'' = -(pi^2 / 2K^2) cos(pi u / K)
// A call on the CPU (host_device.h LOCALIZER_HOST_NOINLINE), as it was before the GPU shared
// it: inlined into the Newton loop, the refined delays moved by ~1e-15 sample.
LOCALIZER_HOST_NOINLINE LOCALIZER_HOST_DEVICE inline SincValue EvaluateSinc(const float* samples, double x) {
  constexpr double kPi = 3.14159265358979323846;
  const double window_angle = kPi * x / kPeakHalfWidth;
  const double cos_a = cos(window_angle);
  const double sin_a = sin(window_angle);
  // sin and cos of pi x = K * window_angle by three angle doublings (K = 8): one sin/cos
  // pair per evaluation instead of two.
  static_assert(kPeakHalfWidth == 8, "the doublings below assume K = 8");
  double sin_pi_x = sin_a;
  double cos_pi_x = cos_a;
  for (int i = 0; i < 3; ++i) {
    const double sin_2 = 2.0 * sin_pi_x * cos_pi_x;
    cos_pi_x = cos_pi_x * cos_pi_x - sin_pi_x * sin_pi_x;
    sin_pi_x = sin_2;
  }
  constexpr double kWindowRate = kPi / kPeakHalfWidth;  // d(pi u / K) / du
  SincValue out;
  for (int m = 0; m < kPeakSamples; ++m) {
    const int j = m - kPeakHalfWidth;
    const double u = x - j;
    if (fabs(u) >= kPeakHalfWidth) continue;  // outside the window: zero with its slope
    const double sign = (j & 1) ? -1.0 : 1.0;
    double sinc, sinc1, sinc2;
    if (fabs(u) < 1e-4) {  // Taylor series: the quotients below lose precision near 0
      sinc = 1.0 - kPi * kPi * u * u / 6.0;
      sinc1 = -kPi * kPi * u / 3.0;
      sinc2 = -kPi * kPi / 3.0;
    } else {
      const double inv_u = 1.0 / u;
      sinc = sign * sin_pi_x * inv_u * (1.0 / kPi);
      sinc1 = (sign * cos_pi_x - sinc) * inv_u;
      sinc2 = -kPi * kPi * sinc - 2.0 * sinc1 * inv_u;
    }
    const double cos_w = cos_a * CosTap(m) + sin_a * SinTap(m);
    const double sin_w = sin_a * CosTap(m) - cos_a * SinTap(m);
    const double hann = 0.5 + 0.5 * cos_w;
    const double hann1 = -0.5 * kWindowRate * sin_w;
    const double hann2 = -0.5 * kWindowRate * kWindowRate * cos_w;
    const double y = samples[m];
    out.value += y * sinc * hann;
    out.slope += y * (sinc1 * hann + sinc * hann1);
    out.curvature += y * (sinc2 * hann + 2.0 * sinc1 * hann1 + sinc * hann2);
  }
  return out;
}

// Newton's method on the reconstruction's slope, from x (the parabolic estimate); converges
// in two or three steps because the start is within a few hundredths of a sample.
LOCALIZER_HOST_DEVICE inline double MaximiseSinc(const float* samples, double x) {
  // A Newton step of size e leaves an error of order e^2: stopping at 1e-4 is ~1e-8 exact.
  constexpr double kTolerance = 1e-4;  // samples
  constexpr int kMaxIterations = 8;
  for (int i = 0; i < kMaxIterations; ++i) {
    const SincValue f = EvaluateSinc(samples, x);
    if (!(f.curvature < 0.0)) break;  // not near a maximum; keep what we have
    const double step = -f.slope / f.curvature;
    x = hd::Clamp(x + step, -1.0, 1.0);
    if (fabs(step) < kTolerance) break;
  }
  return x;
}

// Offset of the true maximum from samples[kPeakHalfWidth], in samples, within [-1, 1].
// Cost: a few ns for the three-point fits; kSinc ~2-3 Newton steps of 17 taps (~0.2 us on a
// CPU core, ~1-2 us on one GPU thread).
LOCALIZER_HOST_DEVICE inline double InterpolatePeak(PeakInterpolation method, const float* samples) {
  const double y_minus = samples[kPeakHalfWidth - 1];
  const double y0 = samples[kPeakHalfWidth];
  const double y_plus = samples[kPeakHalfWidth + 1];
  switch (method) {
    case PeakInterpolation::kParabolic:
      return ParabolicPeakOffset(y_minus, y0, y_plus);
    case PeakInterpolation::kGaussian:
      return GaussianPeakOffset(y_minus, y0, y_plus);
    case PeakInterpolation::kSinc:
      return MaximiseSinc(samples, ParabolicPeakOffset(y_minus, y0, y_plus));
  }
  return 0.0;
}

}  // namespace localizer::engine
