// The recording `localizer-cli track` reads, and its flags: one multichannel WAV or mono WAVs
// (--wav), headerless PCM from a file or a pipe (--raw, clients/io/raw_pcm.h), or live
// capture from an ALSA device (--alsa, clients/io/alsa_capture.h); --channels and
// --sample-rate describe the last two.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "clients/io/alsa_capture.h"
#include "clients/io/raw_pcm.h"
#include "engine/core/flags.h"
#include "engine/core/status.h"

namespace localizer::cli {

struct TrackInputFlags {
  std::vector<std::string> wav_paths;
  std::string raw_path;
  std::string raw_format = "s16le";
  std::optional<int> channels;           // --raw and --alsa
  std::optional<double> sample_rate_hz;  // --raw and --alsa
  std::string alsa_device;
  std::string alsa_format = "best";
  double duration_s = 0.0;
  io::AlsaCaptureOptions alsa;  // --alsa-period, --alsa-buffer, --alsa-timeout, with their defaults
};

void RegisterTrackInputFlags(FlagSet& flags, TrackInputFlags* f);

// What the flags describe: raw PCM, an ALSA device, or (neither set) the WAV files.
struct TrackInput {
  std::optional<io::RawPcmOptions> raw;
  std::optional<io::AlsaCaptureOptions> alsa;
};

// INVALID_ARGUMENT naming the flag for a missing, contradictory or bad one ("--raw and --wav
// both given", "--alsa needs --channels N ...", "--duration needs --alsa").
StatusOr<TrackInput> ParseTrackInput(const FlagSet& flags, const TrackInputFlags& f);

}  // namespace localizer::cli
