// Linear-phase band-pass FIR by the windowed-sinc method, and "valid" FIR filtering.
//
// The ideal band-pass with -6 dB edges f_lo, f_hi (Hz), centred on tap M of 2M + 1:
//     h[n] = w(n) (2 f_hi/fs sinc(2 f_hi (n - M)/fs) - 2 f_lo/fs sinc(2 f_lo (n - M)/fs)),
// sinc(x) = sin(pi x)/(pi x), w a Kaiser window for 60 dB of stopband attenuation. Each
// transition band is centred on its edge; its width is half the narrowest of f_lo,
// fs/2 - f_hi and f_hi - f_lo (a zero f_lo is a low-pass, f_hi = fs/2 no upper edge: those
// terms drop out). The width sets the length, about 3.6 fs / width taps, clamped to
// [63, 4095]; e.g. 300-3000 Hz at 11025 Hz: 150 Hz, 267 taps; 300-8000 Hz at 48 kHz:
// 150 Hz, 1161 taps. Passband ripple and stopband level are both about -60 dB.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

namespace localizer::engine {

struct BandPassFir {
  std::vector<double> taps;  // symmetric, odd length; group delay (size - 1) / 2 samples
  double transition_hz = 0.0;
};

// Requires 0 <= band_low_hz < band_high_hz <= sample_rate_hz / 2 (SimOptions::Validate).
BandPassFir DesignBandPassFir(double band_low_hz, double band_high_hz, double sample_rate_hz);

// y[n] = sum_j taps[j] x[n + j] for n = 0 .. x.size() - taps.size(): the part of the
// convolution with no edge transient. For symmetric taps y[n] is x filtered and aligned with
// x[n + (taps.size() - 1) / 2]. Cost x.size() * taps.size() multiply-adds.
std::vector<double> FilterValid(const std::vector<double>& x, const std::vector<double>& taps);

// n samples of white Gaussian noise from `rng` through DesignBandPassFir(low, high), scaled by
// the taps' energy so that its power is 1 (same requirements on the band).
std::vector<double> UnitPowerBandNoise(double band_low_hz, double band_high_hz, double sample_rate_hz, int64_t n,
                                       std::mt19937_64* rng);

}  // namespace localizer::engine
