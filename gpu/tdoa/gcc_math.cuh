// What the GPU's GCC kernels (gcc_kernels.cu) add to the engine's shared maths: the codes a
// task descriptor carries, the weighting dispatch over those codes, and the parallel forms
// of two reductions. The per-bin weights, floors, lobe rule, quality ratio and the peak
// refinement are the engine's own functions (engine/tdoa/gcc_math.h, peak_math.h,
// engine/core/fast_math.h), compiled here for the device: there is no second copy to keep
// equal. tests/gpu/gcc_math_test.cu runs this header on the host against the CPU stage.
//
// Plain C++ as well: without nvcc the qualifiers vanish (engine/core/host_device.h).
#pragma once

#include <cfloat>
#include <cmath>
#include <cstdint>

#include "engine/core/host_device.h"
#include "engine/tdoa/gcc_math.h"
#include "engine/tdoa/peak_math.h"

namespace localizer::gpu::gcc {

// The codes the kernels read from a task descriptor; the same order as engine::Weighting and
// engine::PeakInterpolation (checked in gcc_batch.cc).
enum WeightingCode : int32_t { kPhat = 0, kPhatBeta = 1, kScot = 2, kCc = 3 };
enum InterpolationCode : int32_t { kParabolic = 0, kGaussian = 1, kSinc = 2 };

// One pair's weighting, fixed for a frame once both channels' energies are known
// (E = sum of squared samples of the frame, double).
struct WeighParams {
  int32_t weighting = kPhat;
  float beta = 0.0f;                // kPhatBeta's exponent
  float floor_mag = 0.0f;           // PHAT, PHAT-beta: |X_k X_r*| >= 1e-12 sqrt(E_k E_r)
  float floor_ref_power = 0.0f;     // SCOT: |X_r|^2 >= 1e-12 E_r
  float floor_sensor_power = 0.0f;  // SCOT: |X_k|^2 >= 1e-12 E_k
};

LOCALIZER_HOST_DEVICE inline WeighParams MakeWeighParams(int32_t weighting, float beta, double energy_ref,
                                                         double energy_sensor) {
  WeighParams p;
  p.weighting = weighting;
  p.beta = beta;
  p.floor_mag = engine::PowerFloor(sqrt(energy_ref * energy_sensor));
  p.floor_ref_power = engine::PowerFloor(energy_ref);
  p.floor_sensor_power = engine::PowerFloor(energy_sensor);
  return p;
}

// G = W X_k conj(X_r) at one in-band bin, and |G| as the CPU adds it to the normaliser
// (W |X_k X_r*|, computed from the magnitude rather than from G).
struct WeighedBin {
  engine::CrossBin g;
  float weighted_mag;
};

LOCALIZER_HOST_DEVICE inline WeighedBin WeighBin(const WeighParams& p, engine::CrossBin xr, engine::CrossBin xk) {
  const engine::CrossBin c = engine::CrossOf(xr, xk);
  const float mag = engine::Magnitude(c);
  float weight = 1.0f;
  float weighted_mag = mag;
  switch (p.weighting) {
    case kPhat:
      weight = engine::PhatWeightOf(mag, p.floor_mag);
      weighted_mag = mag * weight;
      break;
    case kPhatBeta:
      weight = engine::PhatBetaWeightOf(mag, p.floor_mag, p.beta);
      weighted_mag = mag * weight;
      break;
    case kScot:
      weight = engine::ScotWeightOf(engine::PowerOf(xr), engine::PowerOf(xk), p.floor_ref_power, p.floor_sensor_power);
      weighted_mag = mag * weight;
      break;
    default:  // kCc
      break;
  }
  return {{c.re * weight, c.im * weight}, weighted_mag};
}

// S, the sum of |G| over the full Hermitian spectrum of N bins, from the sum over the half
// spectrum (bins 0..N/2, summed in double by the block reduction; the CPU sums float lanes)
// and the real parts of G at DC and Nyquist: bins 1..N/2-1 stand for two bins each. float,
// as the CPU returns it.
LOCALIZER_HOST_DEVICE inline float FullSpectrumNorm(double half_sum, float g_dc_re, float g_nyquist_re) {
  return static_cast<float>(2.0 * half_sum - fabsf(g_dc_re) - fabsf(g_nyquist_re));
}

// One in-band bin's share of the moments behind delay_sigma and the candidates' spacing
// (engine/tdoa/delay_statistics.h, SpectrumMoments): G_k rotated to the measured delay d,
// A_k = G_k exp(j w_k d) = Re + j Im, w_k = 2 pi k / N, c_k = 1 at DC and Nyquist and 2 for
// the bins that stand for a conjugate pair. The CPU rotates by a recurrence in lanes, this by
// sincos per bin: they agree to ~1e-12 relative.
struct BinMoments {
  double level = 0.0;
  double first = 0.0;
  double curvature = 0.0;
  double slope_var = 0.0;
};
LOCALIZER_HOST_DEVICE inline void AddBinMoments(int k, int fft_size, double delay_samples, engine::CrossBin g,
                                                BinMoments* m) {
  const double bin_rate = 6.283185307179586 / fft_size;
  const double angle = bin_rate * delay_samples * k;
  const double c = sin(angle), co = cos(angle);
  const double re = g.re * co - g.im * c;
  const double im = g.re * c + g.im * co;
  const double w = bin_rate * k;
  const double weight = (k == 0 || 2 * k == fft_size) ? 1.0 : 2.0;
  m->level += weight * re;
  m->first += weight * w * re;
  m->curvature += weight * w * w * re;
  m->slope_var += weight * weight * w * w * im * im;
}

// The argmax's partial result: the larger value wins, the smaller index on ties, which is
// std::max_element's "first maximum" whatever order the candidates are combined in.
struct PeakCandidate {
  float value;
  int index;
};
LOCALIZER_HOST_DEVICE inline PeakCandidate NoPeak() { return {-FLT_MAX, 0x7fffffff}; }
LOCALIZER_HOST_DEVICE inline PeakCandidate BetterPeak(PeakCandidate a, PeakCandidate b) {
  if (a.value > b.value) return a;
  if (b.value > a.value) return b;
  return a.index <= b.index ? a : b;
}

// The refinement for a descriptor's interpolation code (engine::InterpolatePeak; an unknown
// code refines nothing).
LOCALIZER_HOST_DEVICE inline double InterpolatePeak(int32_t code, const float* samples) {
  return engine::InterpolatePeak(static_cast<engine::PeakInterpolation>(code), samples);
}

}  // namespace localizer::gpu::gcc
