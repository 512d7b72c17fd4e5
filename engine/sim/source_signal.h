// The emitted source signal s, sampled at the simulation rate on a grid of emission times
// te_n = (n - origin_index) / fs.
//
// kBroadband: white Gaussian noise filtered by DesignBandPassFir(band_low_hz, band_high_hz,
// fs) (band_pass_fir.h), scaled by 1 / sqrt(sum h^2) so that its expected RMS is 1.
// kClicks: a train of band-limited pulses
//     s(t) = sum_i g(t - t_i),  g(t) = blackman(t / T) cos(2 pi f_c t) for |t| < T/2, else 0,
//     f_c = (f_lo + f_hi) / 2,  T = 6 / (f_hi - f_lo),
// so the Blackman main lobe (half-width 3 / T) spans the band and its side lobes (-58 dB)
// keep the pulse band-limited; g(0) = 1 is the peak (300-3000 Hz: a 2.2 ms burst at 1650 Hz).
// Click i is due at i / click_rate_hz and jittered by a uniform draw in +-0.2 / click_rate_hz.
//
// kTonalBroadband: sqrt(1 - F) x the kBroadband noise plus tone_count tones
//     sum_i sqrt(2 F / N) cos(2 pi f_i t + phi_i),  F = tone_power_fraction, N = tone_count,
// so the expected power is still 1, F of it in tones; f_i uniform in the middle 80 % of
// [band_low_hz, band_high_hz] (clear of the noise filter's transitions), phi_i uniform.
//
// Random draws come from std::mt19937_64 engines seeded with std::seed_seq from (seed, stream,
// index): the noise per block of kNoiseBlock grid samples, the jitter per click. So s at a
// given emission time depends only on the options (seed, rate, band), not on the span asked
// for: a longer run extends the same signal, and the same options give bit-identical samples.
#pragma once

#include <cstdint>
#include <vector>

#include "engine/sim/simulator.h"

namespace localizer::engine {

struct SourceWaveform {
  double sample_rate_hz = 0.0;
  int64_t origin_index = 0;  // samples[origin_index] is at emission time 0
  std::vector<double> samples;
  std::vector<double> click_times_s;  // kClicks: peak emission time of each pulse, ascending

  // Fractional sample position of an emission time, for FractionalDelayInterpolator.
  double PositionOf(double emission_time_s) const {
    return emission_time_s * sample_rate_hz + static_cast<double>(origin_index);
  }
};

// s on the smallest grid covering emission times [start_s, end_s] (start_s <= end_s), for
// options that passed SimOptions::Validate. Cost: (end - start) fs x FIR taps for kBroadband.
SourceWaveform MakeSourceWaveform(const SimOptions& options, double start_s, double end_s);

struct Tone {
  double frequency_hz = 0.0;
  double phase_rad = 0.0;
  double amplitude = 0.0;  // peak; the tone's power is amplitude^2 / 2
};
// kTonalBroadband's tones, drawn from options.seed (empty for the other signals).
std::vector<Tone> SourceTones(const SimOptions& options);

// The click pulse g above.
class ClickPulse {
 public:
  ClickPulse(double band_low_hz, double band_high_hz);
  double operator()(double t_s) const;
  double duration_s() const { return duration_s_; }  // T: g is zero outside [-T/2, T/2]
  double centre_hz() const { return centre_hz_; }

 private:
  double centre_hz_;
  double duration_s_;
};

// Peak emission times of the clicks due in [start_s, end_s], ascending.
std::vector<double> ClickEmissionTimes(const SimOptions& options, double start_s, double end_s);

}  // namespace localizer::engine
