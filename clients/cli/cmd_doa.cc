// localizer-cli doa: directions of arrival of the sources in a recording, per frame, for
// an array of any shape (clients/io/doa_runner.h).
#include <cstdio>
#include <sstream>
#include <string>
#include <utility>

#include "clients/cli/commands.h"
#include "clients/io/array_json.h"
#include "clients/io/doa_runner.h"
#include "engine/doa/array_shape.h"
#include "engine/doa/srp_phat.h"

namespace localizer::cli {
namespace {

const char* const kCommand = "doa";

// "x,y,z" -> a vector.
StatusOr<engine::Vec3> ParseVector(const std::string& text) {
  engine::Vec3 v;
  std::stringstream in(text);
  std::string part;
  for (int axis = 0; axis < 3; ++axis) {
    if (!std::getline(in, part, ',')) return InvalidArgument("--source-side needs x,y,z, got '" + text + "'");
    auto value = ParseFiniteDouble(part);
    if (!value.ok()) return InvalidArgument("--source-side: " + value.status().message());
    v(axis) = *value;
  }
  if (std::getline(in, part, ',')) return InvalidArgument("--source-side needs x,y,z, got '" + text + "'");
  return v;
}

}  // namespace

int RunDoa(const std::vector<std::string>& args) {
  std::string array_path, out_path, side_text;
  std::vector<std::string> wav_paths;
  engine::SrpOptions srp;
  int hop_samples = 256;
  std::optional<double> band_low_hz, band_high_hz;
  FlagSet flags("localizer-cli doa --array FILE --wav FILE [--wav FILE ...] --out FILE [flags]",
                "Finds the directions of the sources heard in each frame of a recording (SRP-PHAT over\n"
                "every sensor pair, engine/doa) and writes one CSV row per (frame, source):\n"
                "t_s,peak,source_present,azimuth_rad,elevation_rad,cone_angle_rad,mirror_azimuth_rad,\n"
                "mirror_elevation_rad,statistic,threshold,power_db. Any array of 2 or more sensors:\n"
                "a volumetric array gives directions on the sphere, a planar one directions with their\n"
                "mirror image across its plane (unless --source-side picks the side), a linear one the\n"
                "cone angle to its axis. Far field; no tracking (a peak's rank is not an identity).\n"
                "Prints the array's shape and a summary (frames, frames with a source, peaks, wall time).\n"
                "The array file's \"session\" object gives the defaults of --frame (frame_samples), --hop\n"
                "(hop_samples), --band-low/--band-high (band_low_hz, band_high_hz) and --false-alarm\n"
                "(presence_false_alarm); its tracker settings are not used here.");
  flags.String("array", &array_path, "FILE", "array.json (or the XAV hydrophone CSV): sensors and sound speed")
      .Required();
  flags.Strings("wav", &wav_paths, "FILE", "one multichannel WAV, or one mono WAV per sensor in order").Required();
  flags.String("out", &out_path, "FILE", "the CSV to write").Required();
  flags.Int("frame", &srp.frame_samples, "N", "samples", "frame length");
  flags.Int("hop", &hop_samples, "N", "samples", "frame step, in [1, frame]");
  flags.OptionalDouble("band-low", &band_low_hz, "HZ", "array.json band_hz, else 0", "lowest frequency used");
  flags.OptionalDouble("band-high", &band_high_hz, "HZ", "array.json band_hz, else Nyquist", "highest frequency used");
  flags.Int("max-sources", &srp.max_sources, "K", "sources",
            "most sources reported per frame, in [1, 16] (else the array file's max_sources)");
  flags.Double("false-alarm", &srp.false_alarm, "P", "per frame",
               "probability that noise alone reports a source, per search, in (0, 0.1]");
  flags.String("source-side", &side_text, "X,Y,Z",
               "planar arrays: sources lie where (direction . (X,Y,Z)) > 0, not in the array's plane (default: "
               "the array file's source_side)");
  bool no_diffuse = false;
  flags.Bool("no-diffuse-weighting", &no_diffuse,
             "weigh every frequency alike (by default each sensor pair's frequencies are weighted by how little a "
             "room's diffuse sound correlates across the pair, as in track)");
  std::string signal_weighting;
  flags.String("signal-weighting", &signal_weighting, "on|off",
               "weigh each frame's frequencies by their share of signal, or every frequency alike, as in track "
               "(default: on for planar and volumetric arrays, off for linear ones)");
  if (auto exit_code = ParseFlagsOrExit(kCommand, flags, args)) return *exit_code;
  if (!signal_weighting.empty() && signal_weighting != "on" && signal_weighting != "off")
    return UsageError(kCommand, "--signal-weighting is '" + signal_weighting + "'; give on or off");
  if (!side_text.empty()) {
    auto side = ParseVector(side_text);
    if (!side.ok()) return UsageError(kCommand, side.status().message());
    srp.source_side = *side;
  }

  auto array = io::ReadArrayFile(array_path, io::ArrayUse::kDirection);
  if (!array.ok()) return RuntimeError(kCommand, array.status());
  // The array file's source_side and max_sources, unless the flags say otherwise.
  if (side_text.empty() && array->source_side_normal) srp.source_side = *array->source_side_normal;
  if (!flags.seen("max-sources") && array->max_sources) srp.max_sources = *array->max_sources;
  // Its "session" settings that a direction search reads (no tracking here: the tracker's are
  // not used), unless the flags say otherwise; a session band replaces the band_hz hint, as
  // in track.
  const io::SessionSettings& session = array->session;
  if (!flags.seen("frame") && session.frame_samples) srp.frame_samples = *session.frame_samples;
  if (!flags.seen("hop") && session.hop_samples) hop_samples = *session.hop_samples;
  if (!flags.seen("false-alarm") && session.presence_false_alarm) srp.false_alarm = *session.presence_false_alarm;
  srp.diffuse_weighting = !no_diffuse && session.direction_diffuse_weighting.value_or(true);
  if (signal_weighting.empty() && session.direction_signal_weighting) {
    signal_weighting = *session.direction_signal_weighting ? "on" : "off";
  }
  const bool session_band = session.band_low_hz.value_or(0.0) != 0.0 || session.band_high_hz.value_or(0.0) != 0.0;
  const std::pair<double, double> band =
      session_band ? std::make_pair(session.band_low_hz.value_or(0.0), session.band_high_hz.value_or(0.0))
                   : array->band_hz.value_or(std::make_pair(0.0, 0.0));
  srp.band_low_hz = band_low_hz.value_or(band.first);
  srp.band_high_hz = band_high_hz.value_or(band.second);
  if (signal_weighting.empty()) {  // as a track session decides it
    auto shape = engine::ClassifyArray(array->sensors_m);
    if (!shape.ok()) return RuntimeError(kCommand, shape.status());
    srp.signal_weighting = engine::DefaultSignalWeighting(shape->shape);
  } else {
    srp.signal_weighting = signal_weighting == "on";
  }

  io::DoaJob job;
  job.wav_paths = wav_paths;
  job.array_source = array_path;
  job.sensors_m = array->sensors_m;
  job.sound_speed_mps = array->sound_speed_mps;
  job.array_sample_rate_hz = array->sample_rate_hz;
  job.srp = srp;
  job.hop_samples = hop_samples;
  job.csv_path = out_path;
  auto summary = io::RunDoa(job, [](const std::string& warning) { Warning(kCommand, warning); });
  if (!summary.ok()) return RuntimeError(kCommand, summary.status());
  std::printf("array: %s, %zu sensors\n", engine::ArrayShapeName(summary->shape), array->sensors_m.size());
  std::printf("frames=%lld with_source=%lld peaks=%lld wall_s=%.3f audio_s=%.3f\n",
              static_cast<long long>(summary->frames), static_cast<long long>(summary->frames_with_source),
              static_cast<long long>(summary->peaks), summary->wall_s,
              static_cast<double>(summary->frames) * hop_samples / summary->sample_rate_hz);
  return kExitOk;
}

}  // namespace localizer::cli
