// Scenario simulator: what an array of sensors records from one moving source.
//
// Source signal (source_signal.h): white Gaussian noise band-limited to [band_low_hz,
// band_high_hz] by a linear-phase Kaiser-windowed-sinc FIR (-60 dB outside the band and its
// transitions, band_pass_fir.h) with unit expected RMS, or a train of band-limited clicks
// (impulsive scenes), sampled at the simulation rate over the emission times the run needs.
// Propagation: for each sensor k and output sample time t = n / fs, the emission time te solves
//     te + |p(te) - m_k(t)| / c = t     (fixed-point iteration, converges since |v| << c)
// with m_k(t) the sensor's position at reception (fixed, or carried by a rotating platform:
// SimOptions::platform_attitude)
// and the received value is s(te) / max(|p(te) - m_k|, 1 m) — spherical 1/r spreading and
// a time-varying fractional delay, evaluated by windowed-sinc interpolation of s
// (fractional_delay.h: 32 taps, RMS error ~1e-5 of the signal RMS for content below 0.4 fs).
// Optional surface reflection: an image source mirrored in the plane z = surface_z_m with
// reflection coefficient `surface_reflection` (about -0.9 for a sea surface); optional bottom
// reflection likewise in z = bottom_z_m (`bottom_reflection`, e.g. +0.5 for a hard bottom).
// First-order images only: no surface-bottom multiple bounces.
// Noise: independent white Gaussian per channel, scaled so that each channel's direct-path
// signal power (its mean over the run, measured noiseless) over its noise power is snr_db.
// Impulsive noise (optional): on each channel independently, each sample carries with
// probability impulse_probability an extra symmetric alpha-stable variate
// S1(impulse_alpha, 0, impulse_scale_over_noise_std x the Gaussian noise std, 0)
// (alpha_stable.h). Its scale is tied to the Gaussian noise, so no noise means no impulses.
// Output: channel-major float32 samples and the truth, sampled every truth_step_s of
// reception time at the reference sensor: the source state at the emission instant whose
// sound reaches the reference sensor at that reception time.
// Deterministic: the same options and seed give bit-identical output.
// Cost: channels x samples x (a 32-tap interpolation and 1-2 trajectory evaluations) per
// path, plus the source FIR (source samples x taps); a 60 s, 8-channel, 11025 Hz run of a
// turning source takes about 0.6 s on one core (1.1 s with the surface echo).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "engine/array/array_geometry.h"
#include "engine/sim/platform_motion.h"
#include "engine/sim/trajectory.h"

namespace localizer::engine {

// kTonalBroadband: tone_count tones (frequencies drawn from the seed in the middle 80 % of
// the band, random phases) carrying tone_power_fraction of the unit source power, plus the
// band-limited noise carrying the rest (source_signal.h).
enum class SourceSignal { kBroadband, kClicks, kTonalBroadband };

// snr_db at or above this means no noise at all.
inline constexpr double kNoNoiseSnrDb = 200.0;

struct SimOptions {
  double sample_rate_hz = 11025.0;  // > 0
  double duration_s = 10.0;         // reception time covered, > 0; round(duration * fs)
                                    // samples per channel, at most 2^31 over all channels
  Trajectory trajectory;
  SourceSignal signal = SourceSignal::kBroadband;
  double band_low_hz = 200.0;  // source band, 0 <= low < high <= fs / 2; keep high
                               // well below fs / 2 for accurate fractional delays
  double band_high_hz = 4000.0;
  double click_rate_hz = 20.0;       // kClicks: clicks per second (regular, jittered by seed)
  int tone_count = 3;                // kTonalBroadband: tones, in [1, 16]
  double tone_power_fraction = 0.5;  // kTonalBroadband: share of the power in tones, [0, 1]
  double snr_db = 20.0;              // per channel, direct path; +inf (or >= 200) for no noise
  bool surface_reflection_enabled = false;
  double surface_z_m = 0.0;          // reflecting plane z = surface_z_m
  double surface_reflection = -0.9;  // pressure-release surface: negative, |r| <= 1
  bool bottom_reflection_enabled = false;
  double bottom_z_m = -100.0;                  // reflecting plane z = bottom_z_m
  double bottom_reflection = 0.5;              // hard bottom: positive, |r| <= 1
  double impulse_probability = 0.0;            // per sample and channel, in [0, 1]; 0: no impulses
  double impulse_scale_over_noise_std = 30.0;  // alpha-stable scale / Gaussian noise std, > 0
  double impulse_alpha = 1.5;                  // tail index of the impulses, in (0, 2]
  double truth_step_s = 0.01;                  // spacing of truth rows, >= 1 / fs
  uint64_t seed = 1;
  // A moving array: the sensors given to Simulate are in the platform's body frame and
  // sensor k receives at time t at  At(t) m_k + platform_origin_m  (platform_motion.h); the
  // sound reaching it at t left the source when it left it for that position. Unset: the
  // sensors are fixed in the world.
  std::optional<AttitudeTrajectoryOptions> platform_attitude;
  Vec3 platform_origin_m = Vec3::Zero();

  // INVALID_ARGUMENT naming the field and its value when an option is out of range or not
  // finite (including the trajectory's); OK otherwise.
  Status Validate() const;
};

struct TruthRow {
  double t_s = 0.0;                // reception time at the reference sensor, seconds from the first sample
  Vec3 position_m = Vec3::Zero();  // at the emission instant heard at t_s
  Vec3 velocity_mps = Vec3::Zero();
};

struct SimResult {
  int channel_count = 0;
  int64_t samples_per_channel = 0;
  double sample_rate_hz = 0.0;
  std::vector<float> samples;  // channel-major
  std::vector<TruthRow> truth;

  // Truth linearly interpolated at reception time t_s (clamped to the ends).
  TruthRow TruthAt(double t_s) const;
};

// One channel per sensor of `array`, at its sound speed. INVALID_ARGUMENT (naming the field)
// when options.Validate() fails, when the trajectory's speed is not below half the sound
// speed, or when the run would exceed 2^31 samples (all channels, or the source signal).
// Truth rows at t_s = 0, truth_step_s, ... <= duration_s.
StatusOr<SimResult> Simulate(const ArrayGeometry& array, const SimOptions& options);

// Named scenarios used by the CLI, the demo, tests and benchmarks.
struct Scenario {
  std::string name;
  std::string description;
  std::vector<Vec3> sensors_m;
  double sound_speed_mps = 1500.0;
  SimOptions sim;
};
// "tetra-water": 4 hydrophones on a tetrahedron (~2 m), c = 1500 m/s, 11.025 kHz, CV source.
// "tetra-air": 4 microphones (~0.5 m), c = 343 m/s, 48 kHz, a talker walking a 3 m-radius
//   arc (a constant turn: a straight 10 s walk at 1 m/s cannot stay 2-4 m from the array).
// "turn-multipath": 8 hydrophones, turning source, surface reflection, 5 dB SNR.
// "clicks-water": the tetrahedron with an impulsive click-train source.
// Every parameter, and why, is in scenarios.cc. `seed` goes to sim.seed; an unknown name is
// NOT_FOUND with the valid names listed.
StatusOr<Scenario> MakeScenario(const std::string& name, uint64_t seed = 1);
// In a fixed order: tetra-water, tetra-air, turn-multipath, clicks-water.
std::vector<std::string> ScenarioNames();

}  // namespace localizer::engine
