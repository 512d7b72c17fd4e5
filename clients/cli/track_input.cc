#include "clients/cli/track_input.h"

#include <utility>

namespace localizer::cli {

void RegisterTrackInputFlags(FlagSet& flags, TrackInputFlags* f) {
  flags.Strings("wav", &f->wav_paths, "FILE",
                "one multichannel WAV, or one mono WAV per sensor in sensor order (or --raw, --alsa)");
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
  flags.Double("alsa-period", &f->alsa.period_s, "S", "s",
               "with --alsa: the device's period (how often it delivers), asked for; the device rounds it");
  flags.Double("alsa-buffer", &f->alsa.buffer_s, "S", "s",
               "with --alsa: the device's buffer, asked for: how long tracking may fall behind before samples "
               "are lost (an overrun: counted, and skipped so estimate times stay right)");
  flags.Double("alsa-timeout", &f->alsa.no_data_timeout_s, "S", "s",
               "with --alsa: give up (exit 1) when the device delivers no sample for this long");
  flags.OptionalInt("channels", &f->channels, "N", "",
                    "required with --raw and --alsa: channels per interleaved frame, channel k = sensor k (the "
                    "array's sensor count)");
  flags.OptionalDouble("sample-rate", &f->sample_rate_hz, "HZ", "",
                       "required with --raw and --alsa: samples per second per channel, Hz (wins over the array "
                       "file's)");
}

namespace {

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
Status ReadFormatFlags(const TrackInputFlags& f, const std::string& input, int* channels, double* sample_rate_hz) {
  if (!f.channels) return InvalidArgument(input + " needs --channels N (channels per interleaved frame)");
  if (!f.sample_rate_hz) return InvalidArgument(input + " needs --sample-rate HZ (samples per second per channel)");
  *channels = *f.channels;
  if (*channels < 1 || *channels > io::kMaxRawPcmChannels) {
    return InvalidArgument("--channels is " + std::to_string(*channels) + ", must be in [1, " +
                           std::to_string(io::kMaxRawPcmChannels) + "]");
  }
  *sample_rate_hz = *f.sample_rate_hz;
  if (!(*sample_rate_hz > 0.0)) {
    return InvalidArgument("--sample-rate is " + FormatDouble(*sample_rate_hz) + ", must be > 0");
  }
  return Status::Ok();
}

}  // namespace

StatusOr<TrackInput> ParseTrackInput(const FlagSet& flags, const TrackInputFlags& f) {
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
    return TrackInput{};
  }
  TrackInput choice;
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
  io::AlsaCaptureOptions options = f.alsa;
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

}  // namespace localizer::cli
