// Test signals for the TDOA tests, generated independently of the code under test.
//
// The source is white Gaussian noise made band-limited by zeroing FFT bins outside the band
// on a long circular signal (8x the frame). A channel is a sum of paths s(t - d) * gain,
// each delayed exactly in the frequency domain (multiplying bin f by exp(-j 2 pi f d)), so
// fractional delays carry no interpolation error; the frame is cut from the middle of the
// circular signal, far from where a delay wraps around. Independent white Gaussian noise is
// then added per channel at a given SNR (source power over noise power, full band).
#pragma once

#include <cmath>
#include <complex>
#include <cstdint>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "engine/array/array_geometry.h"
#include "engine/tdoa/fftw_util.h"

namespace localizer::engine::testing {

struct SignalSpec {
  double sample_rate_hz = 11025.0;
  double band_low_hz = 200.0;
  double band_high_hz = 4000.0;
  int frame_samples = 4096;
};

// A talker's band in air at 48 kHz, 8192-sample frames: the source holds 11 % of the bins.
inline SignalSpec TalkerAt48kHz() { return {48000.0, 300.0, 3000.0, 8192}; }

struct Path {
  double delay_samples = 0.0;  // x(t) = gain * s(t - delay)
  double gain = 1.0;
};

inline constexpr double kNoiseless = std::numeric_limits<double>::infinity();

// Channel-major frame; channel c is the sum of channels[c]'s paths of one source (unit RMS
// over the frame on a unit-gain path) plus noise at snr_db (kNoiseless for none).
inline std::vector<float> MultipathFrame(const SignalSpec& spec, const std::vector<std::vector<Path>>& channels,
                                         double snr_db, uint64_t seed) {
  const int frame = spec.frame_samples;
  const int length = NextFastFftSize(8 * frame);
  const int bins = length / 2 + 1;
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> gauss(0.0f, 1.0f);

  FftwFloats time = AllocateFftwFloats(length);
  FftwFloats source = AllocateFftwFloats(2 * bins);
  FftwFloats spectrum = AllocateFftwFloats(2 * bins);
  FftwPlan forward = PlanRealForward(length, time.get(), source.get(), FFTW_ESTIMATE);
  FftwPlan inverse = PlanRealInverse(length, spectrum.get(), time.get(), FFTW_ESTIMATE);

  for (int i = 0; i < length; ++i) time[i] = gauss(rng);
  fftwf_execute(forward.get());
  double band_power = 0.0;  // for unit RMS: Parseval on the kept bins
  for (int k = 0; k < bins; ++k) {
    const double f_hz = k * spec.sample_rate_hz / length;
    const bool keep = f_hz >= spec.band_low_hz && f_hz <= spec.band_high_hz && k < bins - 1;
    if (!keep) source[2 * k] = source[2 * k + 1] = 0.0f;
    const double power = source[2 * k] * source[2 * k] + source[2 * k + 1] * source[2 * k + 1];
    band_power += (k == 0 ? 1.0 : 2.0) * power;
  }
  // Parseval: the source's mean power is band_power / length^2, and the unnormalised inverse
  // transform returns length * source, so this factor gives unit RMS.
  const double to_unit = 1.0 / std::sqrt(band_power);

  const int start = length / 2 - frame / 2;
  std::vector<float> out(channels.size() * frame, 0.0f);
  for (std::size_t c = 0; c < channels.size(); ++c) {
    for (int k = 0; k < bins; ++k) spectrum[2 * k] = spectrum[2 * k + 1] = 0.0f;
    for (const Path& path : channels[c]) {
      for (int k = 0; k < bins; ++k) {
        const double phase = -2.0 * std::numbers::pi * k * path.delay_samples / length;
        const std::complex<double> s(source[2 * k], source[2 * k + 1]);
        const std::complex<double> y = s * std::polar(path.gain * to_unit, phase);
        spectrum[2 * k] += static_cast<float>(y.real());
        spectrum[2 * k + 1] += static_cast<float>(y.imag());
      }
    }
    fftwf_execute(inverse.get());
    for (int i = 0; i < frame; ++i) out[c * frame + i] = time[start + i];
  }
  if (std::isfinite(snr_db)) {
    const float noise_rms = static_cast<float>(std::pow(10.0, -snr_db / 20.0));
    for (float& v : out) v += noise_rms * gauss(rng);
  }
  return out;
}

// One unit-gain path per channel, delayed by delays_samples[c].
inline std::vector<float> DelayedNoiseFrame(const SignalSpec& spec, const std::vector<double>& delays_samples,
                                            double snr_db, uint64_t seed) {
  std::vector<std::vector<Path>> channels;
  for (double d : delays_samples) channels.push_back({Path{d, 1.0}});
  return MultipathFrame(spec, channels, snr_db, seed);
}

// Cramer-Rao bound on the TDOA standard deviation, in samples, for one pair of channels
// from DelayedNoiseFrame at snr_db (Knapp & Carter 1976, flat source and noise spectra):
//     var(D) = [2 T int (2 pi f)^2 snr^2 / (1 + 2 snr) df]^-1  over the source band,
// with T the frame duration and snr the in-band per-hertz SNR: the source's unit power is
// spread over the band, the noise's over 0..fs/2.
inline double TdoaCrbStdSamples(const SignalSpec& spec, double snr_db) {
  const double duration_s = spec.frame_samples / spec.sample_rate_hz;
  const double band_hz = spec.band_high_hz - spec.band_low_hz;
  const double snr = std::pow(10.0, snr_db / 10.0) * (0.5 * spec.sample_rate_hz) / band_hz;
  const double f3 = std::pow(spec.band_high_hz, 3) - std::pow(spec.band_low_hz, 3);
  const double two_pi_sq = 4.0 * std::numbers::pi * std::numbers::pi;
  const double fisher = 2.0 * duration_s * snr * snr / (1.0 + 2.0 * snr) * two_pi_sq * f3 / 3.0;
  return std::sqrt(1.0 / fisher) * spec.sample_rate_hz;
}

// Regular tetrahedron with 2 m edges, centred on the origin.
inline std::vector<Vec3> TetrahedronSensors() {
  const double a = 1.0 / std::sqrt(2.0);  // (+-1, +-1, +-1) corners have 2 sqrt(2) edges
  return {Vec3(a, a, a), Vec3(a, -a, -a), Vec3(-a, a, -a), Vec3(-a, -a, a)};
}

// TetrahedronSensors() as an array underwater (c = 1500 m/s).
inline ArrayGeometry TetrahedronArray() { return *ArrayGeometry::Create(TetrahedronSensors(), 1500.0); }

// Per-channel delay in samples relative to the reference sensor for a source at `source_m`:
// channel c arrives TravelTime(c) - TravelTime(ref) later, which is the pair's TDOA.
inline std::vector<double> ChannelDelaysSamples(const ArrayGeometry& array, const Vec3& source_m,
                                                double sample_rate_hz) {
  std::vector<double> delays;
  const double t_ref = array.TravelTime(source_m, array.reference_sensor());
  for (int c = 0; c < array.sensor_count(); ++c) {
    delays.push_back((array.TravelTime(source_m, c) - t_ref) * sample_rate_hz);
  }
  return delays;
}

}  // namespace localizer::engine::testing
