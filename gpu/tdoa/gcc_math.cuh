// The per-bin and per-window maths of GCC-PHAT as __host__ __device__ functions: the batched
// kernels (gcc_kernels.cu) call them on the device, tests/gpu/gcc_math_test.cu calls the same
// code on the host and compares it with the engine's CPU stage (engine/tdoa/gcc_phat.cc,
// cross_spectrum.h, peak_interpolation.cc). Every function here is a port of one of those,
// line for line where the CPU's order of operations matters (comparisons, floors, casts), so
// the two agree to float rounding: differences come only from FMA contraction and from cuFFT
// versus FFTW, ~1e-6 relative.
//
// Plain C++ as well: without nvcc the qualifiers vanish. No Eigen, no engine headers (the
// constants that must equal the engine's are checked by static_assert in gcc_batch.cc), no
// std:: algorithms (std::max and friends are host-only): ternaries written as the standard
// library writes them, so NaN and tie behaviour match.
#pragma once

#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>

#if defined(__CUDACC__)
#define LOCALIZER_GCC_HD __host__ __device__
#else
#define LOCALIZER_GCC_HD
#endif

namespace localizer::gpu::gcc {

// Equal to engine::kPeakHalfWidth / kPeakSamples, kRelativeFloor (cross_spectrum.h) (all
// three static_assert-ed in gcc_batch.cc) and gcc_phat.cc's quality cap (file-local there,
// so restated by hand: keep the two equal).
inline constexpr int kHalfWidth = 8;
inline constexpr int kPeakSamples = 2 * kHalfWidth + 1;
inline constexpr double kRelativeFloor = 1e-12;
inline constexpr float kQualityCap = 1e9f;

// The codes the kernels read from a task descriptor; the same order as engine::Weighting and
// engine::PeakInterpolation (checked in gcc_batch.cc).
enum WeightingCode : int32_t { kPhat = 0, kPhatBeta = 1, kScot = 2, kCc = 3 };
enum InterpolationCode : int32_t { kParabolic = 0, kGaussian = 1, kSinc = 2 };

// std::max / std::min / std::clamp as the standard library defines them (first argument on
// ties; a NaN first argument wins max, loses clamp's comparisons the same way).
template <typename T>
LOCALIZER_GCC_HD inline T Max(T a, T b) { return a < b ? b : a; }
template <typename T>
LOCALIZER_GCC_HD inline T Min(T a, T b) { return b < a ? b : a; }
template <typename T>
LOCALIZER_GCC_HD inline T Clamp(T v, T lo, T hi) { return v < lo ? lo : (hi < v ? hi : v); }

// ---- Weighting (cross_spectrum.h, gcc_phat.cc WeighCrossSpectrum) --------------------------

struct Cplx {
  float re;
  float im;
};

// X_k conj(X_r).
LOCALIZER_GCC_HD inline Cplx CrossOf(Cplx xr, Cplx xk) {
  return {xk.re * xr.re + xk.im * xr.im, xk.im * xr.re - xk.re * xr.im};
}

LOCALIZER_GCC_HD inline float MagnitudeOf(Cplx c) { return sqrtf(c.re * c.re + c.im * c.im); }

// 1e-12 of a power (sum of squared samples, or its geometric mean for a cross-spectrum) as a
// float within [FLT_MIN, FLT_MAX]: the floor that keeps silent bins finite.
LOCALIZER_GCC_HD inline float FloorOf(double power) {
  return static_cast<float>(Clamp(kRelativeFloor * power, static_cast<double>(FLT_MIN),
                                  static_cast<double>(FLT_MAX)));
}

LOCALIZER_GCC_HD inline float FloatFromBits(int32_t bits) {
#if defined(__CUDA_ARCH__)
  return __int_as_float(bits);
#else
  float f;
  std::memcpy(&f, &bits, sizeof f);
  return f;
#endif
}

LOCALIZER_GCC_HD inline int32_t BitsFromFloat(float f) {
#if defined(__CUDA_ARCH__)
  return __float_as_int(f);
#else
  int32_t bits;
  std::memcpy(&bits, &f, sizeof bits);
  return bits;
#endif
}

// engine::FastExp (fast_math.h): e^x = 2^k e^r, |r| <= ln2 / 2, degree-6 polynomial;
// relative error < 3e-7 on [-87, 88], clamped outside.
LOCALIZER_GCC_HD inline float FastExp(float x) {
  x = x < -87.0f ? -87.0f : (x > 88.0f ? 88.0f : x);
  const float k = roundf(x * 1.44269504088896341f);
  const float r = x - k * 0.693145751953125f - k * 1.428606765330187e-06f;
  float p = 1.0f / 720.0f;
  p = p * r + 1.0f / 120.0f;
  p = p * r + 1.0f / 24.0f;
  p = p * r + 1.0f / 6.0f;
  p = p * r + 0.5f;
  p = p * r + 1.0f;
  p = p * r + 1.0f;
  return p * FloatFromBits((static_cast<int32_t>(k) + 127) << 23);
}

// engine::FastLog: ln x = e ln2 + 2 atanh((m - 1) / (m + 1)), m in [sqrt(1/2), sqrt(2)).
LOCALIZER_GCC_HD inline float FastLog(float x) {
  int32_t bits = BitsFromFloat(x);
  int32_t e = ((bits >> 23) & 0xff) - 127;
  bits = (bits & 0x007fffff) | 0x3f800000;
  float m = FloatFromBits(bits);
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

// One pair's weighting, fixed for a frame once both channels' energies are known
// (E = sum of squared samples of the frame, double).
struct WeighParams {
  int32_t weighting = kPhat;
  float beta = 0.0f;                // kPhatBeta's exponent
  float floor_mag = 0.0f;           // PHAT, PHAT-beta: |X_k X_r*| >= 1e-12 sqrt(E_k E_r)
  float floor_ref_power = 0.0f;     // SCOT: |X_r|^2 >= 1e-12 E_r
  float floor_sensor_power = 0.0f;  // SCOT: |X_k|^2 >= 1e-12 E_k
};

LOCALIZER_GCC_HD inline WeighParams MakeWeighParams(int32_t weighting, float beta, double energy_ref,
                                                    double energy_sensor) {
  WeighParams p;
  p.weighting = weighting;
  p.beta = beta;
  p.floor_mag = FloorOf(sqrt(energy_ref * energy_sensor));
  p.floor_ref_power = FloorOf(energy_ref);
  p.floor_sensor_power = FloorOf(energy_sensor);
  return p;
}

// G = W X_k conj(X_r) at one in-band bin, and |G| as the CPU adds it to the normaliser
// (W |X_k X_r*|, computed from the magnitude rather than from G).
struct WeighedBin {
  Cplx g;
  float weighted_mag;
};

LOCALIZER_GCC_HD inline WeighedBin WeighBin(const WeighParams& p, Cplx xr, Cplx xk) {
  const Cplx c = CrossOf(xr, xk);
  const float mag = MagnitudeOf(c);
  float weight = 1.0f;
  float weighted_mag = mag;
  switch (p.weighting) {
    case kPhat:
      weight = 1.0f / Max(mag, p.floor_mag);
      weighted_mag = mag * weight;
      break;
    case kPhatBeta:
      weight = FastExp(-p.beta * FastLog(Max(mag, p.floor_mag)));
      weighted_mag = mag * weight;
      break;
    case kScot: {
      const float p_ref = xr.re * xr.re + xr.im * xr.im;
      const float p_sensor = xk.re * xk.re + xk.im * xk.im;
      weight = 1.0f / (sqrtf(Max(p_ref, p.floor_ref_power)) *
                       sqrtf(Max(p_sensor, p.floor_sensor_power)));
      weighted_mag = mag * weight;
      break;
    }
    default:  // kCc
      break;
  }
  return {{c.re * weight, c.im * weight}, weighted_mag};
}

// S, the sum of |G| over the full Hermitian spectrum of N bins, from the sum over the half
// spectrum (bins 0..N/2) and the real parts of G at DC and Nyquist: bins 1..N/2-1 stand for
// two bins each. float, as the CPU returns it.
LOCALIZER_GCC_HD inline float FullSpectrumNorm(double half_sum, float g_dc_re, float g_nyquist_re) {
  return static_cast<float>(2.0 * half_sum - fabsf(g_dc_re) - fabsf(g_nyquist_re));
}

// ---- The lag window (gcc_phat.cc MeasurePair) ---------------------------------------------

// Index of lag `lag` in a circular correlation of length n (negative lags wrap to the end).
LOCALIZER_GCC_HD inline int WrapLag(int lag, int n) { return ((lag % n) + n) % n; }

// The argmax's partial result: the larger value wins, the smaller index on ties, which is
// std::max_element's "first maximum" whatever order the candidates are combined in.
struct PeakCandidate {
  float value;
  int index;
};
LOCALIZER_GCC_HD inline PeakCandidate NoPeak() { return {-FLT_MAX, 0x7fffffff}; }
LOCALIZER_GCC_HD inline PeakCandidate BetterPeak(PeakCandidate a, PeakCandidate b) {
  if (a.value > b.value) return a;
  if (b.value > a.value) return b;
  return a.index <= b.index ? a : b;
}

// The main lobe around window index `peak` of a window r(0..size-1): the samples either side
// that stay positive and keep falling. r is any callable int -> float.
template <typename Window>
LOCALIZER_GCC_HD inline void MainLobe(const Window& r, int size, int peak, int* first, int* last) {
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
LOCALIZER_GCC_HD inline void CircularMainLobe(const Circular& at, int n, int peak_lag,
                                              int* first_lag, int* last_lag) {
  int f = peak_lag;
  int l = peak_lag;
  while (l - f < n - 1 && at(f - 1) > 0.0f && at(f - 1) <= at(f)) --f;
  while (l - f < n - 1 && at(l + 1) > 0.0f && at(l + 1) <= at(l)) ++l;
  *first_lag = f;
  *last_lag = l;
}

// peak / sidelobe, capped at 1e9; 1e9 for a positive peak without sidelobe, 0 for none.
LOCALIZER_GCC_HD inline float QualityRatio(float peak, float sidelobe) {
  if (!(sidelobe > 0.0f)) return peak > 0.0f ? kQualityCap : 0.0f;
  return Min(peak / sidelobe, kQualityCap);
}

// ---- Sub-sample refinement (peak_interpolation.cc) ----------------------------------------

LOCALIZER_GCC_HD inline double ParabolicPeakOffset(double y_minus, double y0, double y_plus) {
  const double curvature = y_minus - 2.0 * y0 + y_plus;
  if (!(curvature < 0.0)) return 0.0;
  return Clamp(0.5 * (y_minus - y_plus) / curvature, -1.0, 1.0);
}

LOCALIZER_GCC_HD inline double GaussianPeakOffset(double y_minus, double y0, double y_plus) {
  if (!(y_minus > 0.0 && y0 > 0.0 && y_plus > 0.0)) return ParabolicPeakOffset(y_minus, y0, y_plus);
  return ParabolicPeakOffset(log(y_minus), log(y0), log(y_plus));
}

// cos(k pi / 8) and sin(k pi / 8) for k in [-8, 8]: the Hann window's phase at each tap
// (the CPU's TapTable, here as exact constants so that device code needs no table setup).
LOCALIZER_GCC_HD inline double CosEighthPi(int k) {
  const double table[9] = {1.0,
                           0.92387953251128675613,
                           0.70710678118654752440,
                           0.38268343236508977173,
                           0.0,
                           -0.38268343236508977173,
                           -0.70710678118654752440,
                           -0.92387953251128675613,
                           -1.0};
  return table[k < 0 ? -k : k];
}
LOCALIZER_GCC_HD inline double SinEighthPi(int k) {  // sin(k pi/8) = cos((4 - k) pi/8), k >= 0
  const int a = k < 0 ? -k : k;
  const double s = CosEighthPi(4 - a);
  return k < 0 ? -s : s;
}

struct SincValue {
  double value = 0.0;
  double slope = 0.0;
  double curvature = 0.0;
};

// The Hann-windowed sinc reconstruction sum_m samples[m] k(x - (m - K)) and its first two
// derivatives at x, |x| <= 1 (see engine/tdoa/peak_interpolation.cc for the identities).
LOCALIZER_GCC_HD inline SincValue EvaluateSinc(const float* samples, double x) {
  constexpr double kPi = 3.14159265358979323846;
  const double window_angle = kPi * x / kHalfWidth;
  const double cos_a = cos(window_angle);
  const double sin_a = sin(window_angle);
  double sin_pi_x = sin_a;  // sin and cos of pi x = 8 * window_angle by three doublings
  double cos_pi_x = cos_a;
  for (int i = 0; i < 3; ++i) {
    const double sin_2 = 2.0 * sin_pi_x * cos_pi_x;
    cos_pi_x = cos_pi_x * cos_pi_x - sin_pi_x * sin_pi_x;
    sin_pi_x = sin_2;
  }
  constexpr double kWindowRate = kPi / kHalfWidth;
  SincValue out;
  for (int m = 0; m < kPeakSamples; ++m) {
    const int j = m - kHalfWidth;
    const double u = x - j;
    if (fabs(u) >= kHalfWidth) continue;
    const double sign = (j & 1) ? -1.0 : 1.0;
    double sinc, sinc1, sinc2;
    if (fabs(u) < 1e-4) {
      sinc = 1.0 - kPi * kPi * u * u / 6.0;
      sinc1 = -kPi * kPi * u / 3.0;
      sinc2 = -kPi * kPi / 3.0;
    } else {
      const double inv_u = 1.0 / u;
      sinc = sign * sin_pi_x * inv_u * (1.0 / kPi);
      sinc1 = (sign * cos_pi_x - sinc) * inv_u;
      sinc2 = -kPi * kPi * sinc - 2.0 * sinc1 * inv_u;
    }
    const double cos_tap = CosEighthPi(j);
    const double sin_tap = SinEighthPi(j);
    const double cos_w = cos_a * cos_tap + sin_a * sin_tap;
    const double sin_w = sin_a * cos_tap - cos_a * sin_tap;
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

// Newton's method on the reconstruction's slope from x (the parabolic estimate), to 1e-4
// sample, at most 8 steps, clamped to [-1, 1].
LOCALIZER_GCC_HD inline double MaximiseSinc(const float* samples, double x) {
  constexpr double kTolerance = 1e-4;
  constexpr int kMaxIterations = 8;
  for (int i = 0; i < kMaxIterations; ++i) {
    const SincValue f = EvaluateSinc(samples, x);
    if (!(f.curvature < 0.0)) break;
    const double step = -f.slope / f.curvature;
    x = Clamp(x + step, -1.0, 1.0);
    if (fabs(step) < kTolerance) break;
  }
  return x;
}

// engine::InterpolatePeak: samples[m] = R(peak + m - 8), m = 0..16; returns the offset of the
// refined maximum from the centre sample, in samples, within [-1, 1]. Cost: a few ns for the
// three-point fits; kSinc ~2-3 Newton steps of 17 taps in double (~1-2 us on one GPU thread).
LOCALIZER_GCC_HD inline double InterpolatePeak(int32_t method, const float* samples) {
  const double y_minus = samples[kHalfWidth - 1];
  const double y0 = samples[kHalfWidth];
  const double y_plus = samples[kHalfWidth + 1];
  switch (method) {
    case kParabolic: return ParabolicPeakOffset(y_minus, y0, y_plus);
    case kGaussian: return GaussianPeakOffset(y_minus, y0, y_plus);
    case kSinc: return MaximiseSinc(samples, ParabolicPeakOffset(y_minus, y0, y_plus));
    default: return 0.0;
  }
}

}  // namespace localizer::gpu::gcc
