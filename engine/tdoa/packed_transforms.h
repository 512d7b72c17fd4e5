// Two real transforms for the price of one complex one (the GCC stage's, gcc_phat.h, and the
// direction finder's pair spectra, engine/doa/pair_spectra.h).
//
// Why. With FFTW_ESTIMATE plans (the engine's: they replay bit for bit on every build
// machine, fftw_util.h) a real transform of 5120 points costs about as much as a complex one:
// r2c 6.8, c2r 6.6, c2c 7.2 us on the Sapphire Rapids host (BENCHMARKS.md, issue 20). So two
// channels go through one complex forward transform, and two pairs' weighted cross-spectra
// through one complex inverse, at about 55-60 % of the cost of two real transforms each.
//
// Forward. Channels a and b are the real and imaginary parts of z = x_a + j x_b; with
// Z = FFT(z),
//     X_a(k) = (Z(k) + conj Z(N - k)) / 2,    X_b(k) = (Z(k) - conj Z(N - k)) / (2 j).
// Inverse. Two Hermitian spectra G_a, G_b (their halves, bins 0..N/2) become the full
//     Z(k) = G_a(k) + j G_b(k),   Z(N - k) = conj G_a(k) + j conj G_b(k),
// and IFFT(Z) = r_a + j r_b: both real correlations at once, unnormalised as FFTW's c2r.
// The imaginary parts of DC and Nyquist are ignored, as c2r ignores them.
//
// Exact in exact arithmetic; in float the results differ from r2c / c2r in the last bits
// (the unpacking adds one rounding). Only the bins [first_bin, end_bin) are unpacked or read:
// the callers use no others (their band); the rest of the inverse's input stays zero.
#pragma once

#include "engine/tdoa/fftw_util.h"

namespace localizer::engine {

class PackedTransforms {
 public:
  PackedTransforms() = default;
  // n even (every NextFastFftSize is); 0 <= first_bin < end_bin <= n / 2 + 1. False when FFTW
  // cannot plan the complex transforms of size n.
  bool Init(int n, int first_bin, int end_bin, unsigned flags);

  // 2n floats: x_a(i) at [2i], x_b(i) at [2i + 1]. Write the first frame's samples of each;
  // the rest stays as the caller left it (zero from Init: the transform preserves its input).
  float* forward_input() { return forward_in_.get(); }
  // FFT of forward_input(); bins [first_bin, end_bin) of X_a and X_b into two interleaved
  // (re, im) half spectra (the other bins are not written).
  void Forward(float* spectrum_a, float* spectrum_b);

  // r_a + j r_b from two interleaved half spectra (bins [first_bin, end_bin) read, the rest
  // taken as zero). g_b may be null (taken as zero).
  void Inverse(const float* g_a, const float* g_b);
  // After Inverse: r_a(i) at [2i], r_b(i) at [2i + 1], i = 0..n-1 (lag l at i = l mod n).
  const float* inverse_output() const { return inverse_out_.get(); }

 private:
  void InteriorBins(int* interior_first, int* interior_end) const;

  int n_ = 0;
  int first_bin_ = 0;
  int end_bin_ = 0;
  FftwFloats forward_in_;
  FftwFloats forward_out_;
  FftwFloats inverse_in_;
  FftwFloats inverse_out_;
  FftwFloats zeros_;  // a half spectrum of zeros: Inverse's missing spectrum
  FftwPlan forward_;
  FftwPlan inverse_;
};

}  // namespace localizer::engine
