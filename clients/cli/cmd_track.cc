// localizer-cli track: stream a recording through an engine::Session into estimates.csv.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>

#include "clients/cli/commands.h"
#include "clients/cli/progress.h"
#include "clients/io/array_json.h"
#include "clients/io/track_runner.h"
#include "clients/io/wav_io.h"
#include "engine/pipeline/session.h"

namespace localizer::cli {

namespace {

const char* const kCommand = "track";

// Flag values; the numeric defaults come from engine::SessionConfig.
struct TrackFlags {
  std::string array_path;
  std::vector<std::string> wav_paths;
  std::string out_path;
  engine::SessionConfig config;
  std::string weighting = engine::WeightingName(engine::SessionConfig{}.weighting);
  std::string likelihood = engine::LikelihoodName(engine::SessionConfig{}.filter.likelihood);
  double tdoa_sigma_us = engine::SessionConfig{}.filter.tdoa_sigma_s * 1e6;
  std::optional<double> sound_speed_mps;
  std::optional<int> reference_sensor;
  int print_every = 10;
  double block_s = 0.25;
};

void RegisterFlags(FlagSet& flags, TrackFlags* f) {
  engine::SessionConfig& c = f->config;
  flags
      .String("array", &f->array_path, "FILE",
              "sensor array: array.json, or the XAV hydrophones_config CSV")
      .Required();
  flags
      .Strings("wav", &f->wav_paths, "FILE",
               "one multichannel WAV, or one mono WAV per sensor in sensor order")
      .Required();
  flags.String("out", &f->out_path, "FILE", "estimates CSV to write").Required();
  flags.Int("frame", &c.frame_samples, "N", "samples", "samples per channel per TDOA frame");
  flags.Int("hop", &c.hop_samples, "N", "samples", "samples between frame starts");
  flags.Int("particles", &c.filter.particles, "N", "", "particle count");
  flags.String("weighting", &f->weighting, "NAME", "GCC weighting: phat|phat-beta|scot|cc");
  flags.Double("phat-beta", &c.phat_beta, "B", "", "exponent of --weighting phat-beta, in [0, 1]");
  flags.String("likelihood", &f->likelihood, "NAME",
               "particle likelihood: peak (TDOA peaks) | gcc (whole GCC functions)");
  flags.Uint64("seed", &c.seed, "S", "random seed of the particle filter");
  flags.OptionalDouble("sound-speed", &f->sound_speed_mps, "MPS", "from the array file",
                       "sound speed, m/s");
  flags.OptionalInt("reference", &f->reference_sensor, "K", "from the array file",
                    "reference sensor index");
  flags.Double("band-low", &c.band_low_hz, "HZ", "Hz",
               "lower edge of the GCC band (0: DC, or the array file's band_hz)");
  flags.Double("band-high", &c.band_high_hz, "HZ", "Hz",
               "upper edge of the GCC band (0: Nyquist, or the array file's band_hz)");
  flags.Double("tdoa-sigma-us", &f->tdoa_sigma_us, "US", "us",
               "TDOA noise std of the peak likelihood (0: estimated online from the innovations)");
  flags.Double("accel-noise", &c.filter.accel_noise_mps2, "MPS2", "m/s^2",
               "std of the white acceleration driving the motion model, per axis");
  flags.String("backend", &c.backend, "NAME", "compute backend: cpu|gpu|auto");
  flags.Double("block", &f->block_s, "S", "s", "audio handed to the session per call");
  flags.Int("print-every", &f->print_every, "N", "frames",
            "print every Nth estimate to stdout (0: none)");
}

// The session config from the flags and the array file, with the WAV's sample rate,
// checked by building a session from it.
StatusOr<engine::SessionConfig> BuildConfig(const TrackFlags& f, const io::ArrayFile& array,
                                            double sample_rate_hz) {
  engine::SessionConfig config = f.config;
  auto weighting = engine::ParseWeighting(f.weighting);
  if (!weighting.ok()) return InvalidArgument("--weighting: " + weighting.status().message());
  config.weighting = *weighting;
  auto likelihood = engine::ParseLikelihood(f.likelihood);
  if (!likelihood.ok()) return InvalidArgument("--likelihood: " + likelihood.status().message());
  config.filter.likelihood = *likelihood;
  config.filter.tdoa_sigma_s = f.tdoa_sigma_us * 1e-6;
  config.sensors_m = array.sensors_m;
  config.sound_speed_mps = f.sound_speed_mps.value_or(array.sound_speed_mps);
  config.reference_sensor = f.reference_sensor.value_or(array.reference_sensor);
  config.sample_rate_hz = sample_rate_hz;
  if (config.band_low_hz == 0.0 && config.band_high_hz == 0.0 && array.band_hz) {
    config.band_low_hz = array.band_hz->first;  // the array file's hint, unless flags say
    config.band_high_hz = std::min(array.band_hz->second, 0.5 * sample_rate_hz);
  }
  // Create, not just Validate: some limits (band edges against Nyquist, the backend) are
  // only checked when the stages are built, and a bad flag should fail here as a usage error.
  auto session = engine::Session::Create(config);
  if (!session.ok()) return session.status();
  return config;
}

void PrintEstimate(const engine::Estimate& e) {
  if (!e.initialised) {
    std::printf("frame=%llu t_s=%.3f initialised=0\n",
                static_cast<unsigned long long>(e.frame_index), e.t_s);
    return;
  }
  const auto sd = [&e](int axis) { return std::sqrt(std::max(0.0, e.covariance(axis, axis))); };
  std::printf("frame=%llu t_s=%.3f x_m=%.3f y_m=%.3f z_m=%.3f sx_m=%.3f sy_m=%.3f sz_m=%.3f\n",
              static_cast<unsigned long long>(e.frame_index), e.t_s, e.state[0], e.state[1],
              e.state[2], sd(0), sd(1), sd(2));
}

void PrintSummary(const io::TrackSummary& s, const std::string& out_path) {
  const double speed = s.wall_s > 0 ? s.audio_s() / s.wall_s : 0.0;
  std::printf(
      "frames=%llu initialised=%llu audio_s=%.3f wall_s=%.3f audio_s_per_wall_s=%.1f "
      "tdoa_ms_mean=%.3f filter_ms_mean=%.3f out=%s\n",
      static_cast<unsigned long long>(s.estimates),
      static_cast<unsigned long long>(s.initialised_estimates), s.audio_s(), s.wall_s, speed,
      s.mean_tdoa_s * 1e3, s.mean_filter_s * 1e3, out_path.c_str());
}

io::TrackCallbacks MakeCallbacks(int print_every, ProgressReporter* progress) {
  io::TrackCallbacks callbacks;
  callbacks.on_warning = [](const std::string& message) { Warning(kCommand, message); };
  if (print_every > 0) {
    callbacks.on_estimate = [print_every](const engine::Estimate& e) {
      if (e.frame_index % static_cast<uint64_t>(print_every) == 0) PrintEstimate(e);
    };
  }
  callbacks.on_progress = [progress](const io::TrackProgress& p) { progress->Update(p); };
  return callbacks;
}

}  // namespace

int RunTrack(const std::vector<std::string>& args) {
  TrackFlags f;
  FlagSet flags(
      "localizer-cli track --array FILE --wav FILE [--wav FILE ...] --out FILE [flags]",
      "Streams a recording through one tracking session (GCC TDOAs + particle filter) and\n"
      "writes one row per frame to the estimates CSV. The WAV header's sample rate wins over\n"
      "the array file's. Progress goes to stderr for recordings over 5 s; every Nth estimate\n"
      "and a final summary (frames, wall time, mean stage times) to stdout.");
  RegisterFlags(flags, &f);
  if (auto exit_code = ParseFlagsOrExit(kCommand, flags, args)) return *exit_code;
  if (f.print_every < 0) return UsageError(kCommand, "--print-every must be >= 0");
  if (!(f.block_s > 0)) return UsageError(kCommand, "--block must be > 0");

  auto array = io::ReadArrayFile(f.array_path);
  if (!array.ok()) return RuntimeError(kCommand, array.status());
  // The header's rate is needed to validate the config (band edges against Nyquist).
  double sample_rate_hz = 0.0;
  {
    auto stream = io::WavStream::Open(f.wav_paths);
    if (!stream.ok()) return RuntimeError(kCommand, stream.status());
    sample_rate_hz = stream->sample_rate_hz();
  }
  auto config = BuildConfig(f, *array, sample_rate_hz);
  if (!config.ok()) return UsageError(kCommand, config.status().message());

  io::TrackJob job;
  job.wav_paths = f.wav_paths;
  job.array_source = f.array_path;
  job.array_sample_rate_hz = array->sample_rate_hz;
  job.config = *config;
  job.estimates_csv_path = f.out_path;
  job.block_s = f.block_s;
  ProgressReporter progress;
  auto summary = io::RunTrack(job, MakeCallbacks(f.print_every, &progress));
  progress.Finish();
  if (!summary.ok()) return RuntimeError(kCommand, summary.status());
  PrintSummary(*summary, f.out_path);
  return kExitOk;
}

}  // namespace localizer::cli
