#include "tests/doa/plane_wave.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <random>

#include "engine/tdoa/fftw_util.h"

namespace localizer::engine::testing {

std::vector<float> PlaneWaveFrame(const PlaneWaveScene& scene, const std::vector<PlaneSource>& sources, uint64_t seed) {
  const int n = scene.frame_samples, length = NextFastFftSize(8 * n), bins = length / 2 + 1;
  const double fs = scene.sample_rate_hz;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, std::sqrt(0.5));  // CN(0, 1): each part variance 1/2
  auto in_band = [&](int k) {
    const double f = k * fs / length;
    return k > 0 && k < length / 2 && f >= scene.band_low_hz && f <= scene.band_high_hz;
  };
  std::vector<std::vector<std::complex<double>>> signal(sources.size(), std::vector<std::complex<double>>(bins));
  for (size_t s = 0; s < sources.size(); ++s) {
    const int of = sources[s].echo_of;
    const double f0 = sources[s].harmonic_f0_hz;
    const auto holds = [&](int k) {  // the source has power in bin k
      if (f0 <= 0.0) return true;
      const double f = k * fs / length, below = sources[s].harmonics_below_hz;
      return (below <= 0.0 || f <= below) && std::abs(f - f0 * std::round(f / f0)) <= 20.0;
    };
    for (int k = 0; k < bins; ++k) {
      if (!in_band(k) || !holds(k)) continue;
      if (of >= 0 && static_cast<size_t>(of) < s) {
        const double w = 2.0 * std::numbers::pi * k / length;  // rad per sample
        signal[s][k] =
            sources[s].gain * signal[static_cast<size_t>(of)][k] * std::polar(1.0, -w * sources[s].delay_samples);
      } else {
        signal[s][k] = std::sqrt(sources[s].power) * std::complex<double>(normal(rng), normal(rng));
      }
    }
  }

  FftwFloats spectrum = AllocateFftwFloats(2 * static_cast<size_t>(bins));
  FftwFloats record = AllocateFftwFloats(static_cast<size_t>(length));
  FftwPlan inverse = PlanRealInverse(length, spectrum.get(), record.get(), FFTW_ESTIMATE);
  std::vector<float> frame(scene.sensors_m.size() * static_cast<size_t>(n));
  for (size_t m = 0; m < scene.sensors_m.size(); ++m) {
    for (int k = 0; k < bins; ++k) {
      std::complex<double> x = 0.0;
      if (in_band(k)) {
        const double w = 2.0 * std::numbers::pi * k * fs / length;
        for (size_t s = 0; s < sources.size(); ++s) {
          const double t_s = -scene.sensors_m[m].dot(sources[s].direction) / scene.sound_speed_mps;
          x += signal[s][k] * std::polar(1.0, -w * t_s);
        }
        const double f = k * fs / length;
        const double shape = scene.noise_corner_hz > 0.0 ? 1.0 / (1.0 + std::pow(f / scene.noise_corner_hz, 2)) : 1.0;
        x += std::sqrt(scene.noise_power * shape) * std::complex<double>(normal(rng), normal(rng));
      }
      spectrum[2 * static_cast<size_t>(k)] = static_cast<float>(x.real());
      spectrum[2 * static_cast<size_t>(k) + 1] = static_cast<float>(x.imag());
    }
    fftwf_execute(inverse.get());
    const int start = length / 2 - n / 2;
    for (int i = 0; i < n; ++i) frame[m * static_cast<size_t>(n) + static_cast<size_t>(i)] = record[start + i];
  }
  return frame;
}

double DirectionCrlbRad(const PlaneWaveScene& scene, const Vec3& direction, double snr, bool cone, const Vec3& axis) {
  const int n = scene.frame_samples;
  const double fs = scene.sample_rate_hz, c = scene.sound_speed_mps;
  const double k_sensors = static_cast<double>(scene.sensors_m.size());
  double weight = 0.0;  // sum_k 2 w_k^2 snr^2 / (1 + K snr)
  for (int k = 1; k < n / 2; ++k) {
    const double f = k * fs / n;
    if (f < scene.band_low_hz || f > scene.band_high_hz) continue;
    const double w = 2.0 * std::numbers::pi * f;
    weight += 2.0 * w * w * snr * snr / (1.0 + k_sensors * snr);
  }
  Vec3 mean = Vec3::Zero();
  for (const Vec3& m : scene.sensors_m) mean += m / k_sensors;
  Mat3 spread = Mat3::Zero();
  for (const Vec3& m : scene.sensors_m) spread += (m - mean) * (m - mean).transpose();
  const Mat3 j_u = k_sensors / (c * c) * weight * spread;
  if (cone) {
    const double theta = std::acos(std::clamp(direction.dot(axis), -1.0, 1.0));
    // d u / d theta has length 1 and projects on the axis as -sin(theta).
    const double j_theta = axis.dot(j_u * axis) * std::sin(theta) * std::sin(theta);
    return 1.0 / std::sqrt(j_theta);
  }
  const Vec3 other = std::abs(direction.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  Eigen::Matrix<double, 3, 2> e;
  e.col(0) = direction.cross(other).normalized();
  e.col(1) = direction.cross(e.col(0));
  const Eigen::Matrix2d j = e.transpose() * j_u * e;
  return std::sqrt(j.inverse().trace());
}

double AngleBetween(const Vec3& a, const Vec3& b) { return std::atan2(a.cross(b).norm(), a.dot(b)); }

Vec3 FromAzimuthElevation(double azimuth_rad, double elevation_rad) {
  return {std::cos(elevation_rad) * std::cos(azimuth_rad), std::cos(elevation_rad) * std::sin(azimuth_rad),
          std::sin(elevation_rad)};
}

std::vector<Vec3> Respeaker4() {
  const double a = 0.0405;
  return {Vec3(a, 0, 0), Vec3(0, a, 0), Vec3(-a, 0, 0), Vec3(0, -a, 0)};
}

}  // namespace localizer::engine::testing
