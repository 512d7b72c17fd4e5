#include "engine/sim/simulator.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "engine/sim/alpha_stable.h"
#include "engine/sim/fractional_delay.h"
#include "engine/sim/invalid_value.h"
#include "engine/sim/propagation.h"
#include "engine/sim/seeding.h"
#include "engine/sim/source_signal.h"

namespace localizer::engine {
namespace {

constexpr double kMaxTotalSamples = 2147483648.0;  // 2^31 float samples: 8 GiB
constexpr double kMaxSpeedFractionOfSound = 0.5;   // keeps SolveEmission's iteration short

using sim_detail::Invalid;
using sim_detail::Num;

bool IsPositiveFinite(double value) { return value > 0.0 && std::isfinite(value); }

int64_t SamplesPerChannel(const SimOptions& options) {
  return std::llround(options.duration_s * options.sample_rate_hz);
}

Status ValidateTiming(const SimOptions& o) {
  if (!IsPositiveFinite(o.sample_rate_hz)) {
    return Invalid("sample_rate_hz", o.sample_rate_hz, "must be positive and finite");
  }
  if (!IsPositiveFinite(o.duration_s)) {
    return Invalid("duration_s", o.duration_s, "must be positive and finite");
  }
  const double samples = o.duration_s * o.sample_rate_hz;
  if (samples > kMaxTotalSamples) {
    return Invalid(
        "duration_s", o.duration_s,
        "duration_s * sample_rate_hz = " + Num(samples) + " samples per channel, more than the limit of 2^31");
  }
  if (SamplesPerChannel(o) < 1) {
    return Invalid("duration_s", o.duration_s, "covers no sample at " + Num(o.sample_rate_hz) + " Hz");
  }
  if (!IsPositiveFinite(o.truth_step_s)) {
    return Invalid("truth_step_s", o.truth_step_s, "must be positive and finite");
  }
  // One truth row per sample is the finest useful spacing; it also bounds the row count.
  if (o.truth_step_s * o.sample_rate_hz < 1.0 - 1e-9) {
    return Invalid("truth_step_s", o.truth_step_s,
                   "must be at least one sample period (" + Num(1.0 / o.sample_rate_hz) + " s)");
  }
  return Status::Ok();
}

Status ValidateSignal(const SimOptions& o) {
  const double nyquist_hz = 0.5 * o.sample_rate_hz;
  if (!(o.band_low_hz >= 0.0) || !std::isfinite(o.band_low_hz)) {
    return Invalid("band_low_hz", o.band_low_hz, "must be >= 0 and finite");
  }
  if (!(o.band_high_hz <= nyquist_hz)) {
    return Invalid("band_high_hz", o.band_high_hz, "must be at most sample_rate_hz / 2 = " + Num(nyquist_hz) + " Hz");
  }
  if (!(o.band_low_hz < o.band_high_hz)) {
    return Invalid("band_low_hz", o.band_low_hz, "must be below band_high_hz (" + Num(o.band_high_hz) + " Hz)");
  }
  if (o.signal == SourceSignal::kClicks && !IsPositiveFinite(o.click_rate_hz)) {
    return Invalid("click_rate_hz", o.click_rate_hz, "must be positive and finite");
  }
  if (o.signal == SourceSignal::kTonalBroadband) {
    if (o.tone_count < 1 || o.tone_count > 16) {
      return Invalid("tone_count", o.tone_count, "must lie in [1, 16]");
    }
    if (!(o.tone_power_fraction >= 0.0 && o.tone_power_fraction <= 1.0)) {
      return Invalid("tone_power_fraction", o.tone_power_fraction, "must lie in [0, 1]");
    }
  }
  if (!(o.impulse_probability >= 0.0 && o.impulse_probability <= 1.0)) {
    return Invalid("impulse_probability", o.impulse_probability, "must lie in [0, 1]");
  }
  if (!IsPositiveFinite(o.impulse_scale_over_noise_std)) {
    return Invalid("impulse_scale_over_noise_std", o.impulse_scale_over_noise_std, "must be positive and finite");
  }
  if (!(o.impulse_alpha > 0.0 && o.impulse_alpha <= 2.0)) {
    return Invalid("impulse_alpha", o.impulse_alpha, "must lie in (0, 2]");
  }
  if (std::isnan(o.snr_db) || o.snr_db == -std::numeric_limits<double>::infinity()) {
    return Invalid("snr_db", o.snr_db, "must be a number of dB (>= 200 or +inf: no noise)");
  }
  return Status::Ok();
}

Status ValidateGeometry(const SimOptions& o) {
  if (!std::isfinite(o.surface_z_m)) {
    return Invalid("surface_z_m", o.surface_z_m, "must be finite");
  }
  if (!(std::abs(o.surface_reflection) <= 1.0)) {
    return Invalid("surface_reflection", o.surface_reflection, "must lie in [-1, 1]");
  }
  if (!std::isfinite(o.bottom_z_m)) {
    return Invalid("bottom_z_m", o.bottom_z_m, "must be finite");
  }
  if (!(std::abs(o.bottom_reflection) <= 1.0)) {
    return Invalid("bottom_reflection", o.bottom_reflection, "must lie in [-1, 1]");
  }
  const Trajectory& t = o.trajectory;
  if (!t.position_m.allFinite()) {
    return InvalidArgument("trajectory.position_m has a non-finite coordinate");
  }
  if (!t.velocity_mps.allFinite()) {
    return InvalidArgument("trajectory.velocity_mps has a non-finite component");
  }
  if (!std::isfinite(t.turn_rate_radps)) {
    return Invalid("trajectory.turn_rate_radps", t.turn_rate_radps, "must be finite");
  }
  return Status::Ok();
}

// The direct path (gain 1), then the surface and bottom images when their reflections are on.
struct SourcePath {
  Trajectory trajectory;
  double gain = 1.0;
};
std::vector<SourcePath> SourcePaths(const SimOptions& o) {
  std::vector<SourcePath> paths{{o.trajectory, 1.0}};
  if (o.surface_reflection_enabled) {
    paths.push_back({MirrorInHorizontalPlane(o.trajectory, o.surface_z_m), o.surface_reflection});
  }
  if (o.bottom_reflection_enabled) {
    paths.push_back({MirrorInHorizontalPlane(o.trajectory, o.bottom_z_m), o.bottom_reflection});
  }
  return paths;
}

std::vector<Trajectory> Trajectories(const std::vector<SourcePath>& paths) {
  std::vector<Trajectory> out;
  for (const SourcePath& p : paths) out.push_back(p.trajectory);
  return out;
}

// Checks that need the array, and the source signal's length, before anything is allocated.
Status ValidateAgainstArray(const ArrayGeometry& array, const SimOptions& o, double travel_bound_s) {
  const double c = array.sound_speed_mps();
  const double speed_mps = Speed(o.trajectory);
  if (speed_mps >= kMaxSpeedFractionOfSound * c) {
    return InvalidArgument("trajectory.velocity_mps has speed " + Num(speed_mps) +
                           " m/s; must be below half the sound speed (" + Num(kMaxSpeedFractionOfSound * c) + " m/s)");
  }
  const double total = static_cast<double>(SamplesPerChannel(o)) * array.sensor_count();
  if (total > kMaxTotalSamples) {
    return Invalid(
        "duration_s", o.duration_s,
        "gives " + Num(total) + " samples over " + std::to_string(array.sensor_count()) + " channels, more than 2^31");
  }
  const double source_samples = (travel_bound_s + o.duration_s) * o.sample_rate_hz;
  if (source_samples > kMaxTotalSamples) {
    return InvalidArgument("trajectory.position_m is up to " + Num(travel_bound_s) +
                           " s of travel from the array; the source signal would need " + Num(source_samples) +
                           " samples, more than 2^31");
  }
  return Status::Ok();
}

// Where one sensor is at reception time t: fixed, or carried by the platform.
struct SensorTrack {
  Vec3 body_m;
  const AttitudeTrajectory* platform = nullptr;  // null: fixed at body_m in the world
  Vec3 origin_m = Vec3::Zero();
  Vec3 At(double t_s) const { return platform == nullptr ? body_m : platform->At(t_s) * body_m + origin_m; }
};

// out[n] = gain * s(te_n) / max(r_n, 1 m) for the sound reaching `sensor` at t_n = n / fs
// along `path`: a time-varying fractional delay with spherical spreading.
void RenderPath(const Trajectory& path, const SensorTrack& sensor, double sound_speed_mps, double gain,
                const SourceWaveform& source, const FractionalDelayInterpolator& interpolator,
                std::vector<double>& out) {
  const auto size = static_cast<int64_t>(source.samples.size());
  const double period_s = 1.0 / source.sample_rate_hz;
  double te_before_s = 0.0;  // emission times of the previous two samples
  double te_last_s = 0.0;
  for (size_t n = 0; n < out.size(); ++n) {
    const double t_s = static_cast<double>(n) / source.sample_rate_hz;
    // te(t) is smooth, so extrapolating the last two solutions starts the iteration within
    // ~1e-12 s of the answer: usually one or two trajectory evaluations per sample.
    const double guess_s = n == 0 ? t_s : n == 1 ? te_last_s + period_s : 2.0 * te_last_s - te_before_s;
    const Emission e = SolveEmission(path, sensor.At(t_s), sound_speed_mps, t_s, guess_s);
    te_before_s = te_last_s;
    te_last_s = e.time_s;
    const double s = interpolator.Evaluate(source.samples.data(), size, source.PositionOf(e.time_s));
    out[n] = gain * s / std::max(e.range_m, 1.0);
  }
}

double MeanPower(const std::vector<double>& x) {
  double sum = 0.0;
  for (double v : x) sum += v * v;
  return x.empty() ? 0.0 : sum / static_cast<double>(x.size());
}

// Adds white Gaussian noise of power signal_power / 10^(snr_db / 10) from the channel's own
// engine.
void AddChannelNoise(const SimOptions& o, int channel, double signal_power, std::vector<double>& x) {
  if (o.snr_db >= kNoNoiseSnrDb) return;
  const double sigma = std::sqrt(signal_power * std::pow(10.0, -o.snr_db / 10.0));
  std::mt19937_64 engine = SeededEngine(o.seed, RandomStream::kChannelNoise, channel);
  std::normal_distribution<double> normal(0.0, sigma);
  for (double& v : x) v += normal(engine);
  // Impulses come from their own engine, drawn after the Gaussian noise, so that turning
  // them on leaves the Gaussian part of the channel unchanged.
  if (o.impulse_probability <= 0.0) return;
  std::mt19937_64 impulses = SeededEngine(o.seed, RandomStream::kChannelImpulses, channel);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  AlphaStable stable;
  stable.alpha = o.impulse_alpha;
  stable.scale = o.impulse_scale_over_noise_std * sigma;
  for (double& v : x) {
    if (uniform(impulses) < o.impulse_probability) v += SampleAlphaStable(stable, impulses);
  }
}

std::vector<TruthRow> MakeTruth(const ArrayGeometry& array, const SimOptions& o, const SensorTrack& reference) {
  const auto rows = static_cast<int64_t>(std::floor(o.duration_s / o.truth_step_s + 1e-9)) + 1;
  std::vector<TruthRow> truth(rows);
  for (int64_t i = 0; i < rows; ++i) {
    TruthRow& row = truth[i];
    row.t_s = static_cast<double>(i) * o.truth_step_s;
    const Emission e = SolveEmission(o.trajectory, reference.At(row.t_s), array.sound_speed_mps(), row.t_s);
    row.position_m = o.trajectory.PositionAt(e.time_s);
    row.velocity_mps = o.trajectory.VelocityAt(e.time_s);
  }
  return truth;
}

}  // namespace

Status SimOptions::Validate() const {
  if (!platform_origin_m.allFinite()) return InvalidArgument("platform_origin_m must be finite");
  LOCALIZER_RETURN_IF_ERROR(ValidateTiming(*this));
  LOCALIZER_RETURN_IF_ERROR(ValidateSignal(*this));
  return ValidateGeometry(*this);
}

TruthRow SimResult::TruthAt(double t_s) const {
  if (truth.empty()) return TruthRow{t_s};
  if (t_s <= truth.front().t_s) return truth.front();
  if (t_s >= truth.back().t_s) return truth.back();
  const auto after =
      std::upper_bound(truth.begin(), truth.end(), t_s, [](double t, const TruthRow& row) { return t < row.t_s; });
  const TruthRow& b = *after;
  const TruthRow& a = *(after - 1);
  const double w = (t_s - a.t_s) / (b.t_s - a.t_s);
  TruthRow row;
  row.t_s = t_s;
  row.position_m = (1.0 - w) * a.position_m + w * b.position_m;
  row.velocity_mps = (1.0 - w) * a.velocity_mps + w * b.velocity_mps;
  return row;
}

StatusOr<SimResult> Simulate(const ArrayGeometry& array, const SimOptions& options) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  const double c = array.sound_speed_mps();
  const double fs = options.sample_rate_hz;
  const std::vector<SourcePath> paths = SourcePaths(options);
  const std::vector<Trajectory> path_trajectories = Trajectories(paths);
  std::optional<AttitudeTrajectory> platform;
  if (options.platform_attitude) platform.emplace(*options.platform_attitude);
  std::vector<SensorTrack> sensors;
  double reach_m = 0.0;  // a moving sensor stays within this of the platform origin
  for (const Vec3& m : array.sensors_m()) {
    sensors.push_back({m, platform ? &*platform : nullptr, options.platform_origin_m});
    reach_m = std::max(reach_m, m.norm());
  }
  // A moving sensor is at most reach_m from the origin, which adds at most
  // reach_m / (c - |v|) < 2 reach_m / c (|v| < c / 2) to any travel time.
  const double travel_bound_s =
      platform ? MaxTravelTimeBound(path_trajectories, {options.platform_origin_m}, c, options.duration_s) +
                     2.0 * reach_m / c
               : MaxTravelTimeBound(path_trajectories, array.sensors_m(), c, options.duration_s);
  LOCALIZER_RETURN_IF_ERROR(ValidateAgainstArray(array, options, travel_bound_s));

  // Emission time never exceeds reception time, and precedes it by at most the travel bound;
  // the pad keeps the interpolator's reach on real samples.
  const double pad_s = (FractionalDelayInterpolator::kReach + 2) / fs;
  const SourceWaveform source = MakeSourceWaveform(options, -travel_bound_s - pad_s, options.duration_s + pad_s);
  const FractionalDelayInterpolator interpolator;

  SimResult result;
  result.channel_count = array.sensor_count();
  result.samples_per_channel = SamplesPerChannel(options);
  result.sample_rate_hz = fs;
  result.samples.resize(static_cast<size_t>(result.channel_count * result.samples_per_channel));
  std::vector<double> channel(result.samples_per_channel);
  std::vector<double> reflected(paths.size() > 1 ? channel.size() : 0);
  for (int k = 0; k < result.channel_count; ++k) {
    const SensorTrack& sensor = sensors[static_cast<size_t>(k)];
    RenderPath(paths[0].trajectory, sensor, c, paths[0].gain, source, interpolator, channel);
    const double direct_power = MeanPower(channel);  // the SNR reference
    for (size_t p = 1; p < paths.size(); ++p) {
      RenderPath(paths[p].trajectory, sensor, c, paths[p].gain, source, interpolator, reflected);
      for (size_t n = 0; n < channel.size(); ++n) channel[n] += reflected[n];
    }
    AddChannelNoise(options, k, direct_power, channel);
    float* out = result.samples.data() + static_cast<size_t>(k) * channel.size();
    for (size_t n = 0; n < channel.size(); ++n) out[n] = static_cast<float>(channel[n]);
  }
  result.truth = MakeTruth(array, options, sensors[static_cast<size_t>(array.reference_sensor())]);
  return result;
}

}  // namespace localizer::engine
