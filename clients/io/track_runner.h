// Tracks a recording from WAV files, raw PCM or an ALSA device into estimates: the body of `localizer-cli
// track`, kept in the io library so that tests run exactly the code the command runs.
//
// The recording is streamed in blocks of `block_s` seconds through one engine::Session with
// sequence numbers 1, 2, 3, ...; every Estimate goes to the CSV (when a path is given) and
// to `on_estimate`. Memory stays at one block plus the session's frame ring, whatever the
// file length (raw PCM from a pipe included: it is read as the blocks are needed).
//
// Sample rate: the WAV header (or, for raw PCM, --sample-rate) is what the samples were
// recorded at, so it wins over the array file's sample_rate_hz; a difference is reported
// through `on_warning`.
// Channel count must equal the array's sensor count (INVALID_ARGUMENT naming both).
// A block the session rejects stops the run with the session's message and the block's
// position in the file.
// Samples a live input lost (an overrun; SampleStream::frames_lost_before_last_read) are
// skipped in the session before the next block (engine::Session::Skip), so the frames after
// the gap carry the times of their samples; the summary counts them.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "clients/io/alsa_capture.h"
#include "clients/io/array_json.h"
#include "clients/io/csv_io.h"
#include "clients/io/estimates_writer.h"
#include "clients/io/presence_summary.h"
#include "clients/io/raw_pcm.h"
#include "clients/io/sample_stream.h"
#include "clients/io/wav_io.h"
#include "engine/core/estimate.h"
#include "engine/core/status.h"
#include "engine/pipeline/session.h"

namespace localizer::io {

struct TrackJob {
  std::vector<std::string> wav_paths;          // one multichannel file or mono files per sensor
  std::optional<RawPcmOptions> raw;            // set: read raw PCM (raw_pcm.h) instead of wav_paths
  std::optional<AlsaCaptureOptions> alsa;      // set: capture from an ALSA device (alsa_capture.h) instead
  std::string array_source = "array.json";     // names the array in messages
  std::optional<double> array_sample_rate_hz;  // from the array file, checked against the input's
  engine::AudioSessionConfig config;           // sample_rate_hz is taken from the input (WAV header, raw)
  std::string estimates_path;                  // empty: write no estimates file
  EstimatesFormat estimates_format = EstimatesFormat::kCsv;
  std::optional<GeodeticOrigin> geodetic_origin;  // the array file's; geojson needs it
  double block_s = 0.25;                          // audio per Session::Process call, > 0
};

struct TrackProgress {
  int64_t frames_done = 0;  // samples per channel consumed so far
  int64_t frames_total = 0;
  double sample_rate_hz = 0.0;
  double wall_s = 0.0;  // since the first block
};

struct TrackSummary {
  int64_t samples_per_channel = 0;  // consumed
  int64_t overruns = 0;             // live input: times samples were lost
  int64_t frames_lost = 0;          // live input: samples per channel lost (skipped in the session)
  double sample_rate_hz = 0.0;
  int channel_count = 0;
  uint64_t blocks = 0;
  uint64_t estimates = 0;  // frames processed
  uint64_t initialised_estimates = 0;
  PresenceSummary presence;  // source presence over the run (NoSourceLine)
  double wall_s = 0.0;       // streaming and processing, excluding setup
  double mean_tdoa_s = 0.0;  // mean stage wall time per frame
  double mean_filter_s = 0.0;

  double audio_s() const {
    return sample_rate_hz > 0 ? static_cast<double>(samples_per_channel) / sample_rate_hz : 0.0;
  }
};

struct TrackCallbacks {
  std::function<void(const SampleStream&)> on_opened;        // the input, once opened (its format, for a device)
  std::function<void(const std::string&)> on_warning;        // before processing starts
  std::function<void(const engine::Estimate&)> on_estimate;  // every frame, in order
  std::function<void(const TrackProgress&)> on_progress;     // after every block
};

// `session`, when not null, is a Session already built from job.config (a caller's check of
// the config, e.g. the CLI's): used instead of building a second one when its sample rate is
// the input's (the only field the input sets), else replaced by one built for the input.
StatusOr<TrackSummary> RunTrack(const TrackJob& job, const TrackCallbacks& callbacks = {},
                                std::unique_ptr<engine::Session> session = nullptr);
// RunTrack on an input opened elsewhere (the job's wav_paths, raw and alsa are not used):
// an input kind the job cannot name, or a test's stand-in for a device that loses samples.
StatusOr<TrackSummary> RunTrackOn(std::unique_ptr<SampleStream> stream, const TrackJob& job,
                                  const TrackCallbacks& callbacks = {});

// Flag values that override what the array file says.
struct ArrayOverrides {
  std::optional<double> sound_speed_mps;
  std::optional<int> reference_sensor;
  // Bounds: a whole side of the box (--bounds-min / --bounds-max), then the water column's
  // z sides (--bottom-z / --surface-z) over it.
  std::optional<engine::Vec3> bounds_min_m;
  std::optional<engine::Vec3> bounds_max_m;
  std::optional<double> bottom_z_m;
  std::optional<double> surface_z_m;
};

// The session config `localizer-cli track` runs with, locally or on a server: `config` (the
// user's choices) with the array file's sensors, sound speed and reference sensor unless
// overridden, `sample_rate_hz` (the input's), and, when `config` leaves both band edges
// at 0, the array file's band_hz as the GCC band (its high edge capped at Nyquist); when
// `config` is unbounded, the array file's bounds; then the overrides' bounds. Not validated:
// Session::Create (or the server) does that.
engine::AudioSessionConfig TrackConfigFor(engine::AudioSessionConfig config, const ArrayFile& array,
                                          const ArrayOverrides& overrides, double sample_rate_hz);

// The first half of RunTrack, shared with the remote track (clients/grpc/remote_track.h) so
// that both track a recording with the same session config: opens the WAV(s) (a set's
// truncation note goes to on_warning), the raw PCM input or the ALSA device, checks the channel count against
// job.config's array and sets config.sample_rate_hz from the input (a different array-file
// rate goes to on_warning). The config is not validated here; Session::Create (or the
// server) does that.
struct PreparedTrack {
  std::unique_ptr<SampleStream> stream;  // positioned at the first sample; never null
  engine::AudioSessionConfig config;
};
StatusOr<PreparedTrack> PrepareTrack(const TrackJob& job, const TrackCallbacks& callbacks = {});

}  // namespace localizer::io
