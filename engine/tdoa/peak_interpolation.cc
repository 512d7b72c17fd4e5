#include "engine/tdoa/peak_interpolation.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace localizer::engine {
namespace {

constexpr double kPi = std::numbers::pi;

// cos and sin of pi * j / K for j = -K..K: the window's phase at each tap, so that a kernel
// evaluation needs one sin/cos pair instead of one per tap.
struct TapTable {
  std::array<double, kPeakSamples> cos_tap;
  std::array<double, kPeakSamples> sin_tap;
  TapTable() {
    for (int m = 0; m < kPeakSamples; ++m) {
      const double angle = kPi * (m - kPeakHalfWidth) / kPeakHalfWidth;
      cos_tap[m] = std::cos(angle);
      sin_tap[m] = std::sin(angle);
    }
  }
};

const TapTable& Taps() {
  static const TapTable table;
  return table;
}

// The reconstruction and its first two derivatives at x (offset from the centre sample).
struct SincValue {
  double value = 0.0;
  double slope = 0.0;
  double curvature = 0.0;
};

// With u = x - j for tap j: sin(pi u) = (-1)^j sin(pi x), cos(pi u) = (-1)^j cos(pi x), and
// the window's cos/sin(pi u / K) follow from the angle difference with the tap table, so one
// evaluation needs one sin/cos pair whatever the number of taps.
//   sinc'  = (cos(pi u) - sinc) / u          sinc'' = -pi^2 sinc - 2 sinc' / u
//   hann   = (1 + cos(pi u / K)) / 2         hann'  = -(pi / 2K) sin(pi u / K)
//   hann'' = -(pi^2 / 2K^2) cos(pi u / K)
SincValue EvaluateSinc(std::span<const float, kPeakSamples> samples, double x) {
  const TapTable& taps = Taps();
  const double window_angle = kPi * x / kPeakHalfWidth;
  const double cos_a = std::cos(window_angle);
  const double sin_a = std::sin(window_angle);
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
    if (std::abs(u) >= kPeakHalfWidth) continue;  // outside the window: zero with its slope
    const double sign = (j & 1) ? -1.0 : 1.0;
    double sinc, sinc1, sinc2;
    if (std::abs(u) < 1e-4) {  // Taylor series: the quotients below lose precision near 0
      sinc = 1.0 - kPi * kPi * u * u / 6.0;
      sinc1 = -kPi * kPi * u / 3.0;
      sinc2 = -kPi * kPi / 3.0;
    } else {
      const double inv_u = 1.0 / u;
      sinc = sign * sin_pi_x * inv_u * (1.0 / kPi);
      sinc1 = (sign * cos_pi_x - sinc) * inv_u;
      sinc2 = -kPi * kPi * sinc - 2.0 * sinc1 * inv_u;
    }
    const double cos_w = cos_a * taps.cos_tap[m] + sin_a * taps.sin_tap[m];
    const double sin_w = sin_a * taps.cos_tap[m] - cos_a * taps.sin_tap[m];
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

// Newton's method on the reconstruction's slope, from the parabolic estimate; converges in
// two or three steps because the start is within a few hundredths of a sample.
double MaximiseSinc(std::span<const float, kPeakSamples> samples, double x) {
  // A Newton step of size e leaves an error of order e^2: stopping at 1e-4 is ~1e-8 exact.
  constexpr double kTolerance = 1e-4;  // samples
  constexpr int kMaxIterations = 8;
  for (int i = 0; i < kMaxIterations; ++i) {
    const SincValue f = EvaluateSinc(samples, x);
    if (!(f.curvature < 0.0)) break;  // not near a maximum; keep what we have
    const double step = -f.slope / f.curvature;
    x = std::clamp(x + step, -1.0, 1.0);
    if (std::abs(step) < kTolerance) break;
  }
  return x;
}

}  // namespace

const char* PeakInterpolationName(PeakInterpolation method) {
  switch (method) {
    case PeakInterpolation::kParabolic: return "parabolic";
    case PeakInterpolation::kGaussian: return "gaussian";
    case PeakInterpolation::kSinc: return "sinc";
  }
  return "unknown";
}

double ParabolicPeakOffset(double y_minus, double y0, double y_plus) {
  const double curvature = y_minus - 2.0 * y0 + y_plus;
  if (!(curvature < 0.0)) return 0.0;  // flat or not a maximum: no sub-sample information
  return std::clamp(0.5 * (y_minus - y_plus) / curvature, -1.0, 1.0);
}

double GaussianPeakOffset(double y_minus, double y0, double y_plus) {
  if (!(y_minus > 0.0 && y0 > 0.0 && y_plus > 0.0)) {
    return ParabolicPeakOffset(y_minus, y0, y_plus);
  }
  return ParabolicPeakOffset(std::log(y_minus), std::log(y0), std::log(y_plus));
}

double SincReconstruct(std::span<const float, kPeakSamples> samples, double x) {
  return EvaluateSinc(samples, x).value;
}

double SincCurvature(std::span<const float, kPeakSamples> samples, double x) {
  return EvaluateSinc(samples, x).curvature;
}

double InterpolatePeak(PeakInterpolation method, std::span<const float, kPeakSamples> samples) {
  const double y_minus = samples[kPeakHalfWidth - 1];
  const double y0 = samples[kPeakHalfWidth];
  const double y_plus = samples[kPeakHalfWidth + 1];
  switch (method) {
    case PeakInterpolation::kParabolic: return ParabolicPeakOffset(y_minus, y0, y_plus);
    case PeakInterpolation::kGaussian: return GaussianPeakOffset(y_minus, y0, y_plus);
    case PeakInterpolation::kSinc:
      return MaximiseSinc(samples, ParabolicPeakOffset(y_minus, y0, y_plus));
  }
  return 0.0;
}

}  // namespace localizer::engine
