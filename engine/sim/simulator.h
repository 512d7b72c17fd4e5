// Scenario simulator: what an array of sensors records from one moving source.
//
// Source signal: white Gaussian noise band-limited to [band_low_hz, band_high_hz] (exactly,
// by zeroing FFT bins), unit RMS, or a train of band-limited clicks (impulsive scenes).
// Propagation: for each sensor k and output sample time t, the emission time te solves
//     te + |p(te) - m_k| / c = t        (fixed-point iteration, converges since |v| << c)
// and the received value is s(te) / max(|p(te) - m_k|, 1 m) — spherical 1/r spreading and
// a time-varying fractional delay, evaluated by windowed-sinc interpolation of s.
// Optional surface reflection: an image source mirrored in the plane z = surface_z_m with
// reflection coefficient `surface_reflection` (about -0.9 for a sea surface).
// Noise: independent white Gaussian per channel, scaled so that each channel's direct-path
// signal power over its noise power is snr_db.
// Output: channel-major float32 samples and the truth, sampled every truth_step_s of
// reception time at the reference sensor: the source state at the emission instant whose
// sound reaches the reference sensor at that reception time.
// Deterministic: the same options and seed give bit-identical output.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "engine/array/array_geometry.h"
#include "engine/sim/trajectory.h"

namespace localizer::engine {

enum class SourceSignal { kBroadband, kClicks };

struct SimOptions {
  double sample_rate_hz = 11025.0;  // > 0
  double duration_s = 10.0;         // reception time covered, > 0
  Trajectory trajectory;
  SourceSignal signal = SourceSignal::kBroadband;
  double band_low_hz = 200.0;       // source band, 0 <= low < high <= fs / 2
  double band_high_hz = 4000.0;
  double click_rate_hz = 20.0;      // kClicks: clicks per second (regular, jittered by seed)
  double snr_db = 20.0;             // per channel, direct path; +inf (or >= 200) for no noise
  bool surface_reflection_enabled = false;
  double surface_z_m = 0.0;         // reflecting plane z = surface_z_m
  double surface_reflection = -0.9; // pressure-release surface: negative, |r| <= 1
  double truth_step_s = 0.01;       // spacing of truth rows, > 0
  uint64_t seed = 1;

  Status Validate() const;
};

struct TruthRow {
  double t_s = 0.0;  // reception time at the reference sensor, seconds from the first sample
  Vec3 position_m = Vec3::Zero();    // at the emission instant heard at t_s
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
// "tetra-air": 4 microphones (~0.5 m), c = 343 m/s, 48 kHz, CV source (speaker walking).
// "turn-multipath": 8 hydrophones, turning source, surface reflection, 5 dB SNR.
// "clicks-water": the tetrahedron with an impulsive click-train source.
StatusOr<Scenario> MakeScenario(const std::string& name, uint64_t seed = 1);
std::vector<std::string> ScenarioNames();

}  // namespace localizer::engine
