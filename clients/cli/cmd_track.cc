// localizer-cli track: stream a recording through an engine::Session (or, with --server,
// a session on a localizer-server) into estimates.csv.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <optional>

#include "clients/cli/commands.h"
#include "clients/cli/progress.h"
#include "clients/cli/server_flags.h"
#include "clients/cli/session_flags.h"
#include "clients/grpc/connection.h"
#include "clients/grpc/remote_track.h"
#include "clients/io/alsa_capture.h"
#include "clients/io/array_json.h"
#include "clients/io/raw_pcm.h"
#include "clients/io/track_runner.h"
#include "clients/io/wav_io.h"
#include "engine/pipeline/session.h"

namespace localizer::cli {

namespace {

const char* const kCommand = "track";

// Flag values; the numeric defaults come from engine::AudioSessionConfig.
struct TrackFlags {
  std::string array_path;
  std::vector<std::string> wav_paths;
  // --raw: headerless PCM (clients/io/raw_pcm.h) instead of --wav.
  std::string raw_path;
  std::string raw_format = "s16le";
  std::optional<int> raw_channels;
  std::optional<double> raw_sample_rate_hz;
  // --alsa: live capture from an ALSA device (clients/io/alsa_capture.h), with --channels
  // and --sample-rate as for --raw.
  std::string alsa_device;
  std::string alsa_format = "best";
  double duration_s = 0.0;
  io::AlsaCaptureOptions alsa_defaults;  // period, buffer, timeout defaults
  std::string out_path;
  std::string format = "csv";
  SessionFlags session;
  StreamFlags stream;
  int print_every = 10;
  double block_s = 0.25;
  uint64_t legacy_seed = 0;  // --seed, the old name of --filter-seed
};

void RegisterFlags(FlagSet& flags, TrackFlags* f) {
  flags.String("array", &f->array_path, "FILE", "sensor array: array.json, or the XAV hydrophones_config CSV")
      .Required();
  flags.Strings("wav", &f->wav_paths, "FILE",
                "one multichannel WAV, or one mono WAV per sensor in sensor order (or --raw)");
  flags.String("raw", &f->raw_path, "FILE",
               "instead of --wav: headerless interleaved PCM from FILE, or - for standard input (a pipe from "
               "arecord, sox or ffmpeg is read as it arrives); needs --channels and --sample-rate");
  flags.String("raw-format", &f->raw_format, "FMT",
               "with --raw: s16le | s32le | f32le, little-endian; integers scaled to full scale 1.0 as WAV "
               "samples are (s16 / 32768, s32 / 2^31)");
  flags.String("alsa", &f->alsa_device, "DEVICE",
               std::string("instead of --wav: capture live from an ALSA PCM device (hw:1,0, plughw:CARD=X, default, "
                           "a name from .asoundrc) at exactly --channels and --sample-rate (refused, never "
                           "resampled, if the device cannot); ends after --duration or on SIGINT/SIGTERM, "
                           "writing what was tracked") +
                   (io::AlsaCaptureAvailable() ? "" : std::string("; ") + io::kAlsaUnavailableMessage));
  flags.String("alsa-format", &f->alsa_format, "FMT",
               "with --alsa: the device's sample format: s16 | s32 | f32 (S16_LE, S32_LE, FLOAT_LE), or best: "
               "the first of s32, f32, s16 the device offers");
  flags.Double("duration", &f->duration_s, "S", "s",
               "with --alsa: stop after this much audio (captured plus lost in overruns); 0: until SIGINT/SIGTERM");
  flags.Double("alsa-period", &f->alsa_defaults.period_s, "S", "s",
               "with --alsa: the device's period (how often it delivers), asked for; the device rounds it");
  flags.Double("alsa-buffer", &f->alsa_defaults.buffer_s, "S", "s",
               "with --alsa: the device's buffer, asked for: how long tracking may fall behind before samples "
               "are lost (an overrun: counted, and skipped so estimate times stay right)");
  flags.Double("alsa-timeout", &f->alsa_defaults.no_data_timeout_s, "S", "s",
               "with --alsa: give up (exit 1) when the device delivers no sample for this long");
  flags.OptionalInt("channels", &f->raw_channels, "N", "",
                    "required with --raw and --alsa: channels per interleaved frame, channel k = sensor k (the "
                    "array's sensor count)");
  flags.OptionalDouble("sample-rate", &f->raw_sample_rate_hz, "HZ", "",
                       "required with --raw and --alsa: samples per second per channel, Hz (wins over the array "
                       "file's)");
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

// The input the flags describe: raw PCM, an ALSA device, or (neither set) --wav.
struct InputChoice {
  std::optional<io::RawPcmOptions> raw;
  std::optional<io::AlsaCaptureOptions> alsa;
};

// Which of --raw, --alsa, --wav were given: "--raw and --wav both given".
std::string GivenInputs(bool wav, bool raw, bool alsa) {
  std::vector<std::string> names;
  if (raw) names.push_back("--raw");
  if (alsa) names.push_back("--alsa");
  if (wav) names.push_back("--wav");
  if (names.size() == 3) return "--raw, --alsa and --wav all given";
  return names[0] + " and " + names[1] + " both given";
}

// --channels and --sample-rate, checked, for the input flag `input` ("--raw", "--alsa").
Status ReadFormatFlags(const TrackFlags& f, const std::string& input, int* channels, double* sample_rate_hz) {
  if (!f.raw_channels) return InvalidArgument(input + " needs --channels N (channels per interleaved frame)");
  if (!f.raw_sample_rate_hz) return InvalidArgument(input + " needs --sample-rate HZ (samples per second per channel)");
  *channels = *f.raw_channels;
  if (*channels < 1 || *channels > io::kMaxRawPcmChannels) {
    return InvalidArgument("--channels is " + std::to_string(*channels) + ", must be in [1, " +
                           std::to_string(io::kMaxRawPcmChannels) + "]");
  }
  *sample_rate_hz = *f.raw_sample_rate_hz;
  if (!(*sample_rate_hz > 0.0)) {
    return InvalidArgument("--sample-rate is " + FormatDouble(*sample_rate_hz) + ", must be > 0");
  }
  return Status::Ok();
}

// INVALID_ARGUMENT naming the flag for a missing or contradictory one.
StatusOr<InputChoice> InputOptions(const FlagSet& flags, const TrackFlags& f) {
  const bool wav = !f.wav_paths.empty();
  const bool raw = flags.seen("raw");
  const bool alsa = flags.seen("alsa");
  if (int(wav) + int(raw) + int(alsa) > 1) {
    return InvalidArgument(GivenInputs(wav, raw, alsa) + "; read the recording from one of them");
  }
  if (!wav && !raw && !alsa) {
    return InvalidArgument("no recording: give --wav FILE or --raw FILE (- for standard input), or --alsa DEVICE");
  }
  if (!raw && flags.seen("raw-format")) return InvalidArgument("--raw-format needs --raw");
  if (!alsa) {
    for (const char* name : {"alsa-format", "duration", "alsa-period", "alsa-buffer", "alsa-timeout"}) {
      if (flags.seen(name)) return InvalidArgument(std::string("--") + name + " needs --alsa");
    }
  }
  if (wav) {
    for (const char* name : {"channels", "sample-rate"}) {
      if (flags.seen(name)) return InvalidArgument(std::string("--") + name + " needs --raw or --alsa");
    }
    return InputChoice{};
  }
  InputChoice choice;
  if (raw) {
    if (f.raw_path.empty()) return InvalidArgument("--raw needs a file name, or - for standard input");
    io::RawPcmOptions options;
    options.path = f.raw_path;
    auto format = io::ParseRawPcmFormat(f.raw_format);
    if (!format.ok()) return InvalidArgument("--raw-format: " + format.status().message());
    options.format = *format;
    LOCALIZER_RETURN_IF_ERROR(ReadFormatFlags(f, "--raw", &options.channel_count, &options.sample_rate_hz));
    choice.raw = options;
    return choice;
  }
  if (f.alsa_device.empty()) return InvalidArgument("--alsa needs a device name (hw:1,0, default, ...)");
  io::AlsaCaptureOptions options = f.alsa_defaults;
  options.device = f.alsa_device;
  auto format = io::ParseAlsaSampleFormat(f.alsa_format);
  if (!format.ok()) return InvalidArgument("--alsa-format: " + format.status().message());
  options.format = *format;
  LOCALIZER_RETURN_IF_ERROR(ReadFormatFlags(f, "--alsa", &options.channel_count, &options.sample_rate_hz));
  options.duration_s = f.duration_s;
  if (Status valid = options.Validate(); !valid.ok()) {
    // Name the flags, not the fields.
    std::string m = valid.message();
    for (const auto& [field, flag] : {std::pair<std::string, std::string>{"ALSA sample_rate_hz", "--sample-rate"},
                                      {"ALSA period_s", "--alsa-period"},
                                      {"ALSA buffer_s", "--alsa-buffer"},
                                      {"duration_s", "--duration"},
                                      {"ALSA no_data_timeout_s", "--alsa-timeout"}}) {
      if (m.rfind(field, 0) == 0) m = flag + m.substr(field.size());
    }
    return InvalidArgument(m);
  }
  choice.alsa = options;
  return choice;
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

// Live capture ends cleanly on SIGINT or SIGTERM: the handler only raises the flag the
// capture polls (alsa_capture.h), so the blocks read so far are tracked, the estimates file
// is closed and the summary printed. A second signal is not fatal, because senders such as
// timeout(1) signal the process and its group, i.e. twice; a third kills as usual.
std::atomic<bool> stop_capture{false};
std::atomic<int> stop_signal{0};
std::atomic<int> stop_signals_received{0};
static_assert(std::atomic<bool>::is_always_lock_free && std::atomic<int>::is_always_lock_free,
              "set from a signal handler");

extern "C" void OnStopSignal(int signal_number) {
  if (stop_signals_received.fetch_add(1) >= 2) {
    std::signal(signal_number, SIG_DFL);  // both async-signal-safe
    std::raise(signal_number);
    return;
  }
  if (stop_signal.load() == 0) stop_signal.store(signal_number);
  stop_capture.store(true);
}

void InstallStopHandlers() {
  struct sigaction action {};
  action.sa_handler = OnStopSignal;
  sigemptyset(&action.sa_mask);
  action.sa_flags = 0;  // the capture polls the flag every wait slice (100 ms) anyway
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

// The capture's own figures: what the device delivered, lost and why it ended.
void PrintCaptureSummary(const io::TrackSummary& s, double duration_s) {
  const int signal_number = stop_signal.load();
  const char* stopped = signal_number == SIGINT    ? "SIGINT"
                        : signal_number == SIGTERM ? "SIGTERM"
                        : duration_s > 0           ? "duration"
                                                   : "end";
  std::printf("capture: frames=%lld overruns=%lld samples_lost=%lld stopped_by=%s\n",
              static_cast<long long>(s.samples_per_channel), static_cast<long long>(s.overruns),
              static_cast<long long>(s.frames_lost), stopped);
}

int RunLocal(const TrackFlags& f, const io::TrackJob& job, bool sources) {
  ProgressReporter progress;
  io::TrackCallbacks callbacks = MakeCallbacks(f.print_every, sources, &progress);
  if (job.alsa) {
    InstallStopHandlers();
    callbacks.on_opened = [](const io::SampleStream& stream) {
      const auto* alsa = dynamic_cast<const io::AlsaCaptureStream*>(&stream);
      if (alsa == nullptr) return;
      std::fprintf(stderr, "%s: capturing %d channels at %.0f Hz, %s, period %lld frames, buffer %lld frames\n",
                   alsa->Describe().c_str(), alsa->channel_count(), alsa->sample_rate_hz(),
                   io::RawPcmFormatName(alsa->sample_format()), static_cast<long long>(alsa->period_frames()),
                   static_cast<long long>(alsa->buffer_frames()));
    };
  }
  auto summary = io::RunTrack(job, callbacks);
  progress.Finish();
  if (!summary.ok()) return RuntimeError(kCommand, summary.status());
  PrintSummary(*summary, f.out_path);
  if (job.alsa) PrintCaptureSummary(*summary, job.alsa->duration_s);
  if (auto line = summary->presence.NoSourceLine()) std::printf("%s\n", line->c_str());
  if (auto line = summary->presence.FarFieldLine()) std::printf("%s\n", line->c_str());
  return kExitOk;
}

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
  }
  const auto format = io::ParseEstimatesFormat(f.format);
  if (!format.ok()) return UsageError(kCommand, "--format: " + format.status().message());
  const bool remote = !f.stream.server.empty();
  if (!remote) {
    for (const std::string& name : StreamFlagNames()) {
      if (flags.seen(name)) return UsageError(kCommand, "--" + name + " needs --server");
    }
  } else if (flags.seen("block")) {
    return UsageError(kCommand, "--block is for local tracking; with --server use --block-samples");
  }
  client::RemoteTrackOptions options;
  if (remote) {
    auto parsed = ParseStreamFlags(f.stream);
    if (!parsed.ok()) return UsageError(kCommand, parsed.status().message());
    options = std::move(*parsed);
  }

  auto input = InputOptions(flags, f);
  if (!input.ok()) return UsageError(kCommand, input.status().message());
  // The wire states a gap only as whole missing blocks, so an overrun's exact loss could not
  // reach a server's session; until it can, live capture tracks locally.
  if (input->alsa && remote) {
    return UsageError(kCommand,
                      "--alsa tracks locally (the wire cannot state an overrun's exact gap); to stream to a server, "
                      "pipe arecord into --raw - --server (overruns then go unnoticed)");
  }
  if (input->alsa) {
    input->alsa->stop = &stop_capture;
    if (!io::AlsaCaptureAvailable()) {
      return RuntimeError(kCommand, FailedPrecondition("--alsa " + f.alsa_device + ": " + io::kAlsaUnavailableMessage));
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
    auto stream = io::WavStream::Open(f.wav_paths);
    if (!stream.ok()) return RuntimeError(kCommand, stream.status());
    sample_rate_hz = stream->sample_rate_hz();
  }
  f.session.frame_given = flags.seen("frame");
  f.session.hop_given = flags.seen("hop");
  auto config = BuildSessionConfig(f.session, *array, sample_rate_hz, remote ? Runs::kOnServer : Runs::kLocally);
  if (!config.ok()) return UsageError(kCommand, config.status().message());

  io::TrackJob job;
  job.wav_paths = f.wav_paths;
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
  return remote ? RunOnServer(f, job, *sources, std::move(options)) : RunLocal(f, job, *sources);
}

}  // namespace localizer::cli
