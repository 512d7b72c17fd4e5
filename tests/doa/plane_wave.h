// Test scenes for direction finding: far-field plane waves on an array, synthesised in the
// frequency domain so that every sensor's delay is exact (no interpolation error), and the
// Cramér–Rao bound those scenes allow.
//
// Each source is a white Gaussian signal over [band_low_hz, band_high_hz] (power `power` per
// bin), delayed at sensor m by t_m = -m.u / c; each sensor adds independent Gaussian noise
// over the same band, so the per-bin SNR is power_sum / noise_power = 10^(snr_db / 10) at
// every in-band bin. The record is 8 frames long and circular; the frame returned is its
// middle one, so the delays are true (not circular) within it.
#pragma once

#include <cstdint>
#include <vector>

#include "engine/core/types.h"

namespace localizer::engine::testing {

struct PlaneSource {
  Vec3 direction = Vec3::UnitX();  // unit, from the array towards the source
  double power = 1.0;              // per in-band bin
  // A reflection: when >= 0 (an earlier source's index), this source carries that source's
  // signal scaled by `gain` and delayed by `delay_samples` (power unused, no draw of its own).
  int echo_of = -1;
  double gain = 1.0;
  double delay_samples = 0.0;
  // A voiced talker's spectrum (> 0): power only in the bins within 20 Hz of a multiple of
  // this fundamental, up to harmonics_below_hz (0: the scene's band).
  double harmonic_f0_hz = 0.0;
  double harmonics_below_hz = 0.0;
};

struct PlaneWaveScene {
  std::vector<Vec3> sensors_m;
  double sample_rate_hz = 16000.0;
  double sound_speed_mps = 343.0;
  int frame_samples = 512;
  double band_low_hz = 100.0;
  double band_high_hz = 7000.0;
  double noise_power = 0.1;  // per in-band bin, each sensor
  // Coloured noise (> 0): each sensor's noise power falls as 1 / (1 + (f / this)^2) from
  // noise_power (independent per sensor, as the white noise).
  double noise_corner_hz = 0.0;
};

// sensors x frame_samples floats, channel-major. Seeded: the same seed gives the same frame.
std::vector<float> PlaneWaveFrame(const PlaneWaveScene& scene, const std::vector<PlaneSource>& sources, uint64_t seed);

// Cramér–Rao bound on one frame's direction for one source of per-bin SNR `snr` (stochastic
// signal, K sensors, white noise; verified numerically against tr(R^-1 dR R^-1 dR)):
//     J_tau = sum_k 2 w_k^2 snr^2 / (1 + K snr) (K I - 1 1^T)   over the frame's in-band bins
//     J_u = (K / c^2) sum_k 2 w_k^2 snr^2 / (1 + K snr) sum_m (m - mean)(m - mean)^T.
// Returns the RMS angular error bound in radians: sqrt(trace((E^T J_u E)^-1)) with E the
// tangent plane at u (2 angles); for `cone` (linear arrays) the bound on the cone angle.
double DirectionCrlbRad(const PlaneWaveScene& scene, const Vec3& direction, double snr, bool cone = false,
                        const Vec3& axis = Vec3::Zero());

// A ReSpeaker-style 4-microphone board: microphones at +-4.05 cm on the x and y axes.
std::vector<Vec3> Respeaker4();

// Angle between two unit vectors, radians.
double AngleBetween(const Vec3& a, const Vec3& b);

// A unit vector from azimuth and elevation (radians).
Vec3 FromAzimuthElevation(double azimuth_rad, double elevation_rad);

}  // namespace localizer::engine::testing
