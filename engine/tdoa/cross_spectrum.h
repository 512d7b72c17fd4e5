// The weighted cross-spectrum G = W(f) X_k(f) conj(X_r(f)) over a range of bins: the one
// O(N) loop of GCC besides the FFTs (internal to the tdoa stage; see gcc_phat.h for the maths;
// the per-bin arithmetic is gcc_math.h's, which the GPU kernels share).
//
// Spectra are interleaved (re, im) floats, as FFTW writes them. Each weighting is a small
// functor that, given X_k conj(X_r) at bin b, returns W and |W X_k conj(X_r)|. WeighBins
// works through the bins in L1-sized blocks, two passes per block:
//   1. one fused pass: cross product, magnitude, W (sqrt and divide), G = W X_k conj(X_r)
//      into planar (re[], im[]) scratch, and the normalising sum of |G| kept in kLanes
//      partial sums (GCC will not vectorise a single float accumulator without
//      -fassociative-math);
//   2. interleave the scratch into the inverse transform's input (packed_transforms.h).
// Why planar scratch rather than storing interleaved pairs from pass 1: GCC vectorises a
// loop that stores (re, im) pairs by keeping re and im in alternate lanes, so the sqrt and
// divide ran on every value twice. Measured on the Zen 4 build machine (AVX-512), PHAT over
// 4097 bins with the spectra in L1: fused interleaved 3.5 us, planar scratch 1.5 us; inside
// Estimate (spectra streamed from L2) about 2 us per pair, mostly memory traffic: without
// the sqrt and divide it is 1.8 us, and weighing all pairs in one pass (reading X_r once)
// saved only 0.5 us per 3 pairs, not worth the extra buffers.
#pragma once

#include <algorithm>
#include <cmath>

#include "engine/tdoa/gcc_math.h"

namespace localizer::engine {

inline constexpr int kLanes = 16;  // one 512-bit register of floats

// Bin i of an interleaved spectrum.
inline CrossBin BinAt(const float* x, int i) { return {x[2 * i], x[2 * i + 1]}; }

// X_k conj(X_r) at bin i.
inline CrossBin CrossAt(const float* xr, const float* xk, int i) { return CrossOf(BinAt(xr, i), BinAt(xk, i)); }

// What a weighting gives for one bin: W, and |W G| for the normalising sum.
struct BinWeight {
  float weight;
  float weighted_mag;
};

// W = 1 / max(|G|, floor).
struct PhatWeight {
  float floor_mag;
  BinWeight operator()(CrossBin c, const float*, const float*, int) const {
    const float mag = Magnitude(c);
    const float weight = PhatWeightOf(mag, floor_mag);
    return {weight, mag * weight};
  }
};

// W = w[i] / max(|G|, floor): PHAT scaled by a per-bin weight w >= 0 (kPhatCoherence's
// w(f) = c^2 / (1 - c^2), learnt over earlier frames; see gcc_phat.h).
struct CoherencePhatWeight {
  float floor_mag;
  const float* bin_weight;  // indexed by bin
  BinWeight operator()(CrossBin c, const float*, const float*, int i) const {
    const float mag = Magnitude(c);
    const float weight = bin_weight[i] / std::max(mag, floor_mag);
    return {weight, mag * weight};
  }
};

// W = max(|G|, floor)^-beta = exp(-beta ln max(|G|, floor)), with the vectorisable FastExp
// and FastLog of engine/core/fast_math.h (powf would be a scalar call per bin; it cost more
// than the FFTs). Their float rounding of an exponent up to ~88 bounds the relative error of
// W near 1e-5, plenty for a weighting. FastExp flushes below e^-87, so W would become 0 only
// for |G| > 6e37.
struct PhatBetaWeight {
  float floor_mag;
  float beta;
  BinWeight operator()(CrossBin c, const float*, const float*, int) const {
    const float mag = Magnitude(c);
    const float weight = PhatBetaWeightOf(mag, floor_mag, beta);
    return {weight, mag * weight};
  }
};

// W = 1 / sqrt(max(|X_k|^2, floor_k) max(|X_r|^2, floor_r)); two square roots so the
// product of two floors (each >= FLT_MIN) cannot underflow to zero.
struct ScotWeight {
  float floor_ref_power;
  float floor_sensor_power;
  BinWeight operator()(CrossBin c, const float* xr, const float* xk, int i) const {
    const float weight =
        ScotWeightOf(PowerOf(BinAt(xr, i)), PowerOf(BinAt(xk, i)), floor_ref_power, floor_sensor_power);
    return {weight, Magnitude(c) * weight};
  }
};

// W = 1.
struct CcWeight {
  BinWeight operator()(CrossBin c, const float*, const float*, int) const { return {1.0f, Magnitude(c)}; }
};

inline constexpr int kBlockBins = 256;  // 2 spectra x 2 KiB + 2 KiB of scratch: in L1

// Writes the weighted cross-spectrum for bins [lo, hi) and returns the sum of |G| over them.
template <typename Weight>
float WeighBins(const float* xr, const float* xk, int lo, int hi, const Weight& weight, float* g) {
  alignas(64) float g_re[kBlockBins];
  alignas(64) float g_im[kBlockBins];
  float lanes[kLanes] = {};
  for (int first = lo; first < hi; first += kBlockBins) {
    const int count = std::min(kBlockBins, hi - first);
    const auto weigh = [&](int j, int lane) {
      const int b = first + j;
      const CrossBin c = CrossAt(xr, xk, b);
      const BinWeight w = weight(c, xr, xk, b);
      g_re[j] = c.re * w.weight;
      g_im[j] = c.im * w.weight;
      lanes[lane] += w.weighted_mag;
    };
    int j = 0;
    for (; j + kLanes <= count; j += kLanes) {
      for (int l = 0; l < kLanes; ++l) weigh(j + l, l);
    }
    for (; j < count; ++j) weigh(j, 0);
    for (int k = 0; k < count; ++k) {
      g[2 * (first + k)] = g_re[k];
      g[2 * (first + k) + 1] = g_im[k];
    }
  }
  float sum = 0.0f;
  for (float lane : lanes) sum += lane;
  return sum;
}

}  // namespace localizer::engine
