// Sub-sample refinement of a correlation peak found at an integer lag.
//
// Input: the correlation at integer lags around the peak, samples[m] = R(peak + m - K) for
// m = 0..2K (K = kPeakHalfWidth = 8), samples[K] being the integer maximum. Output: the
// offset delta (samples) such that the refined peak lies at lag peak + delta; |delta| <= 0.5
// when the centre sample is a local maximum, and it is always clamped to [-1, 1].
//
// Methods (y-, y0, y+ are the three samples around the peak):
//   kParabolic  vertex of the parabola through (y-, y0, y+):
//                 delta = (y- - y+) / (2 (y- - 2 y0 + y+))
//               A GCC peak is not a parabola, so the estimate is pulled towards the nearest
//               sample: an odd, S-shaped bias in the true fraction, zero at 0 and 0.5.
//   kGaussian   the same fit on ln y (exact for a Gaussian-shaped peak); falls back to
//               kParabolic when a sample is <= 0. On a band-pass GCC it over-corrects.
//   kSinc       band-limited reconstruction of R between samples,
//                 R(peak + x) = sum_m samples[m] k(x - (m - K)),
//                 k(u) = sinc(u) (1 + cos(pi u / K)) / 2 for |u| < K, else 0
//               (Hann-windowed sinc, sinc(u) = sin(pi u) / (pi u)), maximised by Newton
//               steps on its analytic first and second derivatives, started at the
//               kParabolic estimate (2-3 steps, to 1e-4 sample). Accurate while the
//               correlation's spectrum stays well inside fs/2 (the windowed kernel's pass
//               band), as it does for a GCC over a band-limited source. Cost: about 0.2 us
//               per peak (one sin/cos pair and 17 taps per step) against 3 ns for
//               kParabolic.
//
// Measured by tests/tdoa/peak_interpolation_test.cc: GCC-PHAT with the band set to the
// source's band, band-limited Gaussian noise (fs 11025 Hz, 200..4000 Hz, frame 4096), true
// fractions 0, 0.1, ..., 1.0 sample, 16 frames x 3 pairs per fraction; bias = mean error
// at a fraction, std = spread at a fraction (worst over the fractions), rms = all pooled:
//                     no added noise                 20 dB SNR per channel
//   method      max |bias|   std      rms       max |bias|   std      rms
//   kParabolic  0.056        0.0020   0.038     0.055        0.0040   0.038
//   kGaussian   0.116        0.0031   0.065     0.119        0.0079   0.067
//   kSinc       0.0003       0.0012   0.0011    0.0011       0.0032   0.0029
// (rectangular frames; GccOptions::taper_fraction's default 0.2 takes kSinc's noiseless rms
// to 0.00035 by quieting the frame ends, gcc_phat.h.)
// kSinc is the default (GccOptions::interpolation): it removes the bias and the rms error
// falls 35x (noiseless) and 13x (20 dB). Without the band set, on a noiseless band-limited
// source PHAT whitens the out-of-band leakage of the frame edges and every method scatters
// by 0.12-0.17 sample; at 20 dB without the band, kSinc gives 0.005 bias / 0.018 std and
// kParabolic 0.057 / 0.023 (LeavingOutTheBandSpreadsTheEstimates checks the spread).
//
// The arithmetic (the enum, K, the three-point fits, the sinc reconstruction and its Newton
// search) is in peak_math.h, which the GPU's peak kernel compiles too.
#pragma once

#include <span>

#include "engine/tdoa/peak_math.h"

namespace localizer::engine {

const char* PeakInterpolationName(PeakInterpolation method);

// Offset of the true maximum from the centre sample, in samples; see above. (The CPU's entry
// point, compiled out of line in peak_interpolation.cc as it always was; the GPU calls
// peak_math.h's InterpolatePeak(method, const float*) directly.)
double InterpolatePeak(PeakInterpolation method, std::span<const float, kPeakSamples> samples);

// The Hann-windowed sinc reconstruction of the samples at offset x from the centre sample,
// |x| <= 1 (exposed for tests).
double SincReconstruct(std::span<const float, kPeakSamples> samples, double x);

// Its second derivative (per sample^2) at x, |x| <= 1: the peak's curvature, from which
// gcc_phat.h derives a candidate's delay standard deviation.
double SincCurvature(std::span<const float, kPeakSamples> samples, double x);

}  // namespace localizer::engine
