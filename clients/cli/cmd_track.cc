// localizer-cli track: stream a recording through an engine::Session (or, with --server,
// a session on a localizer-server) into estimates.csv.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>

#include "clients/cli/capture_signals.h"
#include "clients/cli/commands.h"
#include "clients/cli/progress.h"
#include "clients/cli/server_flags.h"
#include "clients/cli/session_flags.h"
#include "clients/cli/track_input.h"
#include "clients/io/alsa_capture.h"
#include "clients/io/array_json.h"
#include "clients/io/raw_pcm.h"
#include "clients/io/track_runner.h"
#include "clients/io/wav_io.h"
#include "engine/pipeline/session.h"
#ifdef LOCALIZER_CLI_OFFLINE
#include "clients/cli/full_cli.h"
#else
#include "clients/cli/server_stream.h"
#include "clients/grpc/connection.h"
#include "clients/grpc/remote_track.h"
#endif

namespace localizer::cli {

namespace {

const char* const kCommand = "track";

// Flag values; the numeric defaults come from engine::AudioSessionConfig.
struct TrackFlags {
  std::string array_path;
  TrackInputFlags input;  // --wav, --raw or --alsa (track_input.h)
  std::string out_path;
  std::string format = "csv";
  SessionFlags session;
  StreamFlags stream;
  int print_every = 10;
  double block_s = 0.25;
  uint64_t legacy_seed = 0;  // --seed, the old name of --filter-seed
};

void RegisterFlags(FlagSet& flags, TrackFlags* f) {
  flags
      .String("array", &f->array_path, "FILE",
              "sensor array: array.json (its optional \"session\" object sets the defaults of the session "
              "flags; a flag given wins), or the XAV hydrophones_config CSV")
      .Required();
  RegisterTrackInputFlags(flags, &f->input);
  flags.String("out", &f->out_path, "FILE", "estimates file to write (--format)").Required();
  flags.String("format", &f->format, "FMT",
               "csv (one row per frame, or per frame and source) | jsonl (one JSON object per frame, "
               "sources nested; non-finite numbers null) | geojson (a FeatureCollection of WGS84 points; needs "
               "the array file's geodetic_origin with heading_deg)");
  // --filter-seed, as in simulate (where --seed is the scene's); --seed is its old name.
  RegisterTrackerFlags(flags, &f->session, "filter-seed");
  flags.Uint64("seed", &f->legacy_seed, "S", "deprecated: the old name of --filter-seed (says so on stderr)");
  RegisterGccFlags(flags, &f->session);
  flags.Double("block", &f->block_s, "S", "s", "audio handed to the local session per call");
  flags.Int("print-every", &f->print_every, "N", "frames", "print every Nth estimate to stdout (0: none)");
  RegisterServerFlag(flags, &f->stream.server, /*required=*/false, &f->stream.connect);
  RegisterStreamFlags(flags, &f->stream, "max");
}

constexpr double kDegPerRad = 180.0 / 3.14159265358979323846;

// Direction sessions: the frame, then per source its id, status and angles in degrees.
void PrintSources(const engine::Estimate& e) {
  std::printf("frame=%llu t_s=%.3f sources=%zu", static_cast<unsigned long long>(e.frame_index), e.t_s,
              e.sources.size());
  for (const engine::SourceEstimate& s : e.sources) {
    std::printf(" [id=%llu %s", static_cast<unsigned long long>(s.source_id), engine::TrackStatusName(s.status));
    if (std::isfinite(s.cone_angle_rad)) {
      std::printf(" cone_deg=%.1f", s.cone_angle_rad * kDegPerRad);
    } else {
      std::printf(" az_deg=%.1f el_deg=%.1f", s.azimuth_rad * kDegPerRad, s.elevation_rad * kDegPerRad);
    }
    std::printf(" sd_deg=%.1f", s.sigma_rad * kDegPerRad);
    if (s.position_m.allFinite()) {
      std::printf(" x_m=%.3f y_m=%.3f z_m=%.3f range_sd_m=%.3f", s.position_m.x(), s.position_m.y(), s.position_m.z(),
                  s.range_sd_m);
    }
    std::printf("]");
  }
  std::printf("\n");
}

void PrintEstimate(const engine::Estimate& e, bool sources) {
  if (sources) {
    PrintSources(e);
    return;
  }
  if (!e.initialised) {
    std::printf("frame=%llu t_s=%.3f initialised=0\n", static_cast<unsigned long long>(e.frame_index), e.t_s);
    return;
  }
  const auto sd = [&e](int axis) { return std::sqrt(std::max(0.0, e.covariance(axis, axis))); };
  std::printf("frame=%llu t_s=%.3f x_m=%.3f y_m=%.3f z_m=%.3f sx_m=%.3f sy_m=%.3f sz_m=%.3f\n",
              static_cast<unsigned long long>(e.frame_index), e.t_s, e.state[0], e.state[1], e.state[2], sd(0), sd(1),
              sd(2));
}

void PrintSummary(const io::TrackSummary& s, const std::string& out_path) {
  const double speed = s.wall_s > 0 ? s.audio_s() / s.wall_s : 0.0;
  std::printf(
      "frames=%llu initialised=%llu audio_s=%.3f wall_s=%.3f audio_s_per_wall_s=%.1f "
      "tdoa_ms_mean=%.3f filter_ms_mean=%.3f out=%s\n",
      static_cast<unsigned long long>(s.estimates), static_cast<unsigned long long>(s.initialised_estimates),
      s.audio_s(), s.wall_s, speed, s.mean_tdoa_s * 1e3, s.mean_filter_s * 1e3, out_path.c_str());
}

io::TrackCallbacks MakeCallbacks(int print_every, bool sources, ProgressReporter* progress) {
  io::TrackCallbacks callbacks;
  callbacks.on_warning = [](const std::string& message) { Warning(kCommand, message); };
  if (print_every > 0) {
    callbacks.on_estimate = [print_every, sources](const engine::Estimate& e) {
      if (e.frame_index % static_cast<uint64_t>(print_every) == 0) PrintEstimate(e, sources);
    };
  }
  callbacks.on_progress = [progress](const io::TrackProgress& p) { progress->Update(p); };
  return callbacks;
}

// What only a server run needs (localizer-cli-full).
#ifndef LOCALIZER_CLI_OFFLINE
// The local run's summary, from what a server stream delivered.
io::TrackSummary SummaryOf(const client::RemoteTrackResult& r, int channel_count) {
  io::TrackSummary s;
  s.samples_per_channel = r.stream.samples_sent_per_channel;
  s.sample_rate_hz = r.sample_rate_hz;
  s.channel_count = channel_count;
  s.blocks = r.stream.blocks_sent;
  s.estimates = r.stream.estimates.size();
  s.wall_s = r.stream.wall_s;
  double tdoa_s = 0.0;
  double filter_s = 0.0;
  for (const client::StreamedEstimate& e : r.stream.estimates) {
    if (e.estimate.initialised) ++s.initialised_estimates;
    s.presence.Add(e.estimate);
    tdoa_s += e.estimate.timings.tdoa_s;
    filter_s += e.estimate.timings.filter_s;
  }
  if (s.estimates > 0) {
    s.mean_tdoa_s = tdoa_s / static_cast<double>(s.estimates);
    s.mean_filter_s = filter_s / static_cast<double>(s.estimates);
  }
  return s;
}

client::StreamCallbacks RejectionWarnings() {
  client::StreamCallbacks callbacks;
  callbacks.on_rejected = [](const client::BlockRejection& r) {
    Warning(kCommand,
            "block " + std::to_string(r.sequence) + " rejected: " + r.code + " (" + r.reason + "): " + r.message);
  };
  callbacks.on_gap = [](const v1::SequenceGap& g) {
    Warning(kCommand, "sequence gap: " + std::to_string(g.missing_blocks()) + " block(s) missing after " +
                          std::to_string(g.previous_sequence()));
  };
  return callbacks;
}
#endif

// The capture's own figures: what the device delivered, lost and why it ended.
void PrintCaptureSummary(const io::TrackSummary& s, double duration_s) {
  const char* stopped = CaptureStopReason(duration_s);
  std::printf("capture: frames=%lld overruns=%lld samples_lost=%lld stopped_by=%s\n",
              static_cast<long long>(s.samples_per_channel), static_cast<long long>(s.overruns),
              static_cast<long long>(s.frames_lost), stopped);
}

// `checked`: the session BuildSessionConfig built from job.config, run instead of a second.
int RunLocal(const TrackFlags& f, const io::TrackJob& job, bool sources, std::unique_ptr<engine::Session> checked) {
  ProgressReporter progress;
  io::TrackCallbacks callbacks = MakeCallbacks(f.print_every, sources, &progress);
  if (job.alsa) {
    InstallCaptureStopHandlers();
    callbacks.on_opened = [](const io::SampleStream& stream) {
      const auto* alsa = dynamic_cast<const io::AlsaCaptureStream*>(&stream);
      if (alsa == nullptr) return;
      std::fprintf(stderr, "%s: capturing %d channels at %.0f Hz, %s, period %lld frames, buffer %lld frames\n",
                   alsa->Describe().c_str(), alsa->channel_count(), alsa->sample_rate_hz(),
                   io::RawPcmFormatName(alsa->sample_format()), static_cast<long long>(alsa->period_frames()),
                   static_cast<long long>(alsa->buffer_frames()));
    };
  }
  auto summary = io::RunTrack(job, callbacks, std::move(checked));
  progress.Finish();
  if (!summary.ok()) return RuntimeError(kCommand, summary.status());
  PrintSummary(*summary, f.out_path);
  if (job.alsa) PrintCaptureSummary(*summary, job.alsa->duration_s);
  if (auto line = summary->presence.NoSourceLine()) std::printf("%s\n", line->c_str());
  if (auto line = summary->presence.FarFieldLine()) std::printf("%s\n", line->c_str());
  return kExitOk;
}

#ifndef LOCALIZER_CLI_OFFLINE
int RunOnServer(const TrackFlags& f, const io::TrackJob& job, bool sources, client::RemoteTrackOptions options) {
  options.on_opened = PrintOpened;
  ProgressReporter progress;
  auto channel = client::Connect(f.stream.server, f.stream.connect);
  if (!channel.ok()) return RuntimeError(kCommand, channel.status());
  auto result = client::RunRemoteTrack(*channel, job, options, MakeCallbacks(f.print_every, sources, &progress),
                                       RejectionWarnings());
  progress.Finish();
  if (!result.ok()) return RuntimeError(kCommand, result.status());
  PrintSummary(SummaryOf(*result, static_cast<int>(job.config.sensors_m.size())), f.out_path);
  PrintStreamTotals(result->stream);
  const Status status = result->stream.status();
  if (!status.ok()) return RuntimeError(kCommand, status);
  return kExitOk;
}
#endif

}  // namespace

int RunTrack(const std::vector<std::string>& args) {
  TrackFlags f;
  FlagSet flags(
      "localizer-cli track --array FILE (--wav FILE [--wav FILE ...] | --raw FILE|- --channels N "
      "--sample-rate HZ [--raw-format FMT] | --alsa DEVICE --channels N --sample-rate HZ [--alsa-format FMT] "
      "[--duration S]) --out FILE [--format csv|jsonl|geojson] [--server HOST:PORT] [flags]",
      "Streams a recording through one tracking session (GCC TDOAs + particle filter) and\n"
      "writes one row per frame to the estimates CSV (--format jsonl: one JSON object per line). Planar and linear "
      "arrays (and\n"
      "--localization direction) give directions instead: SRP-PHAT peaks followed by a\n"
      "direction tracker, up to --max-sources sources with ids, one CSV row per frame and\n"
      "source; with --localization position (a planar array with --source-side, a linear one\n"
      "with --source-plane and --source-side) each heard source also gets x_m, y_m, z_m where\n"
      "the frame bounds its range. The WAV header's sample rate wins over the array file's. Progress goes to stderr "
      "for recordings over 5 "
      "s; every Nth estimate\n"
      "and a final summary (frames, wall time, mean stage times) to stdout.\n"
      "--raw reads headerless PCM instead (e.g. `arecord -t raw -f S16_LE -c 4 -r 48000 |\n"
      "localizer-cli track --raw - --channels 4 --sample-rate 48000 ...`), block by block, in\n"
      "constant memory; the same samples give the same estimates as a WAV file. Trailing bytes\n"
      "that do not make a whole frame are an error (exit 1, after the whole frames before them\n"
      "were tracked): the input does not match --channels and --raw-format. Progress needs a\n"
      "known length, so it is not shown for a pipe.\n"
      "--alsa captures from an ALSA device instead, at exactly --channels and --sample-rate (a\n"
      "device that cannot is refused, naming what it offers); until --duration or SIGINT/SIGTERM,\n"
      "after which the estimates so far are written and the summary printed, with a line\n"
      "\"capture: frames=N overruns=K samples_lost=M stopped_by=...\". Samples lost in an\n"
      "overrun are skipped in the session, so estimate times stay those of their samples.\n"
      "With --server the session runs on a localizer-server: the same config is sent with\n"
      "every field explicit, the recording is streamed in blocks of --block-samples, and the\n"
      "CSV holds the same numbers as a local run with the same flags (the server runs the same\n"
      "engine; only the stage times differ, and only when both use the same backend). The\n"
      "summary adds the client latency (block sent -> estimate received) p50/p95/p99 and the\n"
      "count of blocks the server rejected. A run in which no frame held a source ends with\n"
      "\"no source found in N frames (presence statistic max X, threshold Y)\".");
  RegisterFlags(flags, &f);
  if (auto exit_code = ParseFlagsOrExit(kCommand, flags, args)) return *exit_code;
  if (f.print_every < 0) return UsageError(kCommand, "--print-every must be >= 0");
  if (!(f.block_s > 0)) return UsageError(kCommand, "--block must be > 0");
  if (flags.seen("seed")) {
    if (flags.seen("filter-seed")) return UsageError(kCommand, "--seed is the old name of --filter-seed; give one");
    std::fprintf(stderr,
                 "localizer-cli track: --seed is deprecated, use --filter-seed (the filter's seed; in "
                 "simulate --seed is the scene's)\n");
    f.session.config.seed = f.legacy_seed;
    f.session.also_given.insert("filter-seed");  // over the array file's session seed, as --filter-seed
  }
  const auto format = io::ParseEstimatesFormat(f.format);
  if (!format.ok()) return UsageError(kCommand, "--format: " + format.status().message());
  const bool remote = !f.stream.server.empty();
#ifdef LOCALIZER_CLI_OFFLINE
  if (remote) return ExecFullCli("track --server");  // main sent it there already (NeedsFullCli)
#endif
  if (!remote) {
    for (const std::string& name : StreamFlagNames()) {
      if (flags.seen(name)) return UsageError(kCommand, "--" + name + " needs --server");
    }
  } else if (flags.seen("block")) {
    return UsageError(kCommand, "--block is for local tracking; with --server use --block-samples");
  }
#ifndef LOCALIZER_CLI_OFFLINE
  client::RemoteTrackOptions options;
  if (remote) {
    auto parsed = ParseStreamFlags(f.stream);
    if (!parsed.ok()) return UsageError(kCommand, parsed.status().message());
    options = std::move(*parsed);
  }
#endif

  auto input = ParseTrackInput(flags, f.input);
  if (!input.ok()) return UsageError(kCommand, input.status().message());
  // The wire states a gap only as whole missing blocks, so an overrun's exact loss could not
  // reach a server's session; until it can, live capture tracks locally.
  if (input->alsa && remote) {
    return UsageError(kCommand,
                      "--alsa tracks locally (the wire cannot state an overrun's exact gap); to stream to a server, "
                      "pipe arecord into --raw - --server (overruns then go unnoticed)");
  }
  if (input->alsa) {
    input->alsa->stop = CaptureStopFlag();
    if (!io::AlsaCaptureAvailable()) {
      return RuntimeError(kCommand,
                          FailedPrecondition("--alsa " + f.input.alsa_device + ": " + io::kAlsaUnavailableMessage));
    }
  }

  auto array = io::ReadArrayFile(f.array_path, io::ArrayUse::kAuto);
  if (!array.ok()) return RuntimeError(kCommand, array.status());
  if (Status needs = io::CheckFormatNeeds(*format, array->geodetic_origin); !needs.ok()) {
    return UsageError(kCommand, "--format " + f.format + ": " + f.array_path + ": " + needs.message());
  }
  // The input's rate is needed to validate the config (band edges against Nyquist). For raw
  // PCM it is the flag's: opening standard input here would be harmless, but needless.
  double sample_rate_hz = 0.0;
  if (input->raw || input->alsa) {
    const int channels = input->raw ? input->raw->channel_count : input->alsa->channel_count;
    if (channels != static_cast<int>(array->sensors_m.size())) {
      return UsageError(kCommand, "--channels is " + std::to_string(channels) + " but " + f.array_path + " has " +
                                      std::to_string(array->sensors_m.size()) +
                                      " sensors; they must match (channel k = sensor k)");
    }
    sample_rate_hz = input->raw ? input->raw->sample_rate_hz : input->alsa->sample_rate_hz;
  } else {
    auto stream = io::WavStream::Open(f.input.wav_paths);
    if (!stream.ok()) return RuntimeError(kCommand, stream.status());
    sample_rate_hz = stream->sample_rate_hz();
  }
  std::unique_ptr<engine::Session> checked;
  auto config =
      BuildSessionConfig(f.session, flags, *array, sample_rate_hz, remote ? Runs::kOnServer : Runs::kLocally, &checked);
  if (!config.ok()) return UsageError(kCommand, config.status().message());

  io::TrackJob job;
  job.wav_paths = f.input.wav_paths;
  job.raw = input->raw;
  job.alsa = input->alsa;
  job.array_source = f.array_path;
  job.array_sample_rate_hz = array->sample_rate_hz;
  job.config = *config;
  job.estimates_path = f.out_path;
  job.estimates_format = *format;
  job.geodetic_origin = array->geodetic_origin;
  job.block_s = f.block_s;
  auto sources = engine::ReportsSources(job.config);  // BuildSessionConfig checked it
  if (!sources.ok()) return UsageError(kCommand, sources.status().message());
#ifdef LOCALIZER_CLI_OFFLINE
  return RunLocal(f, job, *sources, std::move(checked));
#else
  return remote ? RunOnServer(f, job, *sources, std::move(options)) : RunLocal(f, job, *sources, std::move(checked));
#endif
}

}  // namespace localizer::cli
