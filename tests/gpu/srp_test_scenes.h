// Shared by the GPU SRP-PHAT tests and benchmark: arrays, seeded plane-wave frames analysed by
// the CPU's engine::SrpPhat, and that frame's pair spectra G_p(k) as the GPU batch takes them.
//
// The spectra are recovered from the CPU analyser's own exact GCC (PairSpectra is the only
// holder of G and keeps it private): R_p(l) at the M integer lags l = 0..M-1
// (PairSpectra::WholeValueAt) determines the in-band bins exactly, since for 0 < k < M/2
//     sum_l R_p(l) exp(-2 pi i k l / M) = M G_p(k) / (2 B)
// (R_p = (1/B) sum_k Re(G_p(k) exp(2 pi i k l / M)), pair_spectra.h). So the GPU is given the
// engine's spectra to double rounding, not a second implementation of PHAT.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <complex>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

#include "engine/doa/srp_phat.h"
#include "gpu/srp/srp_array.h"
#include "tests/doa/plane_wave.h"

namespace localizer::gpu::testing {

using engine::Vec3;

inline std::vector<Vec3> Respeaker4() {  // planar, 8.1 cm across (the ODAS board)
  const double a = 0.0405;
  return {Vec3(a, 0, 0), Vec3(0, a, 0), Vec3(-a, 0, 0), Vec3(0, -a, 0)};
}
inline std::vector<Vec3> Tetra4() {  // volumetric
  const double a = 0.05;
  return {Vec3(a, a, a), Vec3(a, -a, -a), Vec3(-a, a, -a), Vec3(-a, -a, a)};
}
inline std::vector<Vec3> Circle7() {  // planar, centre and six around
  std::vector<Vec3> s{Vec3::Zero()};
  for (int k = 0; k < 6; ++k)
    s.push_back(0.0463 * Vec3(std::cos(k * std::numbers::pi / 3), std::sin(k * std::numbers::pi / 3), 0));
  return s;
}
inline std::vector<Vec3> Line8() {  // linear, 28 cm
  std::vector<Vec3> s;
  for (int k = 0; k < 8; ++k) s.push_back(Vec3(0.04 * k, 0, 0));
  return s;
}
// `sensors` microphones uniform in a cube of `side_m` (volumetric in practice), seeded.
inline std::vector<Vec3> RandomArray(int sensors, double side_m, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> coordinate(-0.5 * side_m, 0.5 * side_m);
  std::vector<Vec3> s;
  for (int i = 0; i < sensors; ++i) s.emplace_back(coordinate(rng), coordinate(rng), coordinate(rng));
  return s;
}

// 4 mics' rate and frames: 256 samples at 16 kHz (hop 128), band 100-7000 Hz.
inline engine::SrpOptions FrameOptions(int frame_samples = 256) {
  engine::SrpOptions o;
  o.sample_rate_hz = 16000.0;
  o.sound_speed_mps = 343.0;
  o.frame_samples = frame_samples;
  o.hop_samples = frame_samples / 2;
  o.band_low_hz = 100.0;
  o.band_high_hz = 7000.0;
  o.max_sources = 1;  // nothing removed: the spectra stay the frame's whole
  return o;
}

// A plane wave of per-bin SNR `snr` from `direction` (no source: power 0) on `sensors`.
inline std::vector<float> PlaneWave(const std::vector<Vec3>& sensors, const engine::SrpOptions& o,
                                    const Vec3& direction, double snr, uint64_t seed) {
  engine::testing::PlaneWaveScene scene;
  scene.sensors_m = sensors;
  scene.sample_rate_hz = o.sample_rate_hz;
  scene.sound_speed_mps = o.sound_speed_mps;
  scene.frame_samples = o.frame_samples;
  scene.band_low_hz = o.band_low_hz;
  scene.band_high_hz = o.band_high_hz;
  scene.noise_power = 1.0;
  return engine::testing::PlaneWaveFrame(scene, {engine::testing::PlaneSource{direction, snr}}, seed);
}

// The pair spectra of the frame `srp` last analysed: P x B values, pair-major, in double.
inline std::vector<std::complex<double>> RecoveredSpectra(const engine::SrpPhat& srp, const SrpArrayModel& model) {
  const int m = model.fft_size, bins = model.band.bins;
  std::vector<std::complex<double>> out(static_cast<size_t>(model.pairs) * static_cast<size_t>(bins));
  std::vector<double> r(static_cast<size_t>(m));
  for (int p = 0; p < model.pairs; ++p) {
    for (int l = 0; l < m; ++l) r[static_cast<size_t>(l)] = srp.spectra().WholeValueAt(p, l).r;
    for (int b = 0; b < bins; ++b) {
      const int k = model.band.first_bin + b;
      std::complex<double> sum = 0.0;
      for (int l = 0; l < m; ++l) {
        // k l mod M keeps the angle small, so its cos and sin are exact to rounding.
        const double angle = -2.0 * std::numbers::pi * static_cast<double>((static_cast<int64_t>(k) * l) % m) / m;
        sum += r[static_cast<size_t>(l)] * std::complex<double>(std::cos(angle), std::sin(angle));
      }
      out[static_cast<size_t>(p) * bins + b] = sum * (2.0 * bins / m);
    }
  }
  return out;
}

inline std::vector<std::complex<float>> AsFloat(const std::vector<std::complex<double>>& g) {
  std::vector<std::complex<float>> out;
  out.reserve(g.size());
  for (const std::complex<double>& v : g) out.emplace_back(static_cast<float>(v.real()), static_cast<float>(v.imag()));
  return out;
}

// Angle between unit vectors, radians (acos is ill-conditioned near 0: atan2 of cross and dot).
inline double AngleRad(const Vec3& a, const Vec3& b) { return std::atan2(a.cross(b).norm(), a.dot(b)); }

}  // namespace localizer::gpu::testing
