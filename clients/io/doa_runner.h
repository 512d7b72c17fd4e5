// Directions of arrival from a recording: the body of `localizer-cli doa`, kept in the io
// library so that tests run exactly the code the command runs.
//
// The recording (one multichannel WAV or one mono WAV per sensor) is cut into frames of
// frame_samples every hop_samples (engine/pipeline/framer.h) and each frame goes through one
// engine::SrpPhat (engine/doa/srp_phat.h). The CSV gets, per frame, one row per source found
// (peak = 0, 1, ... strongest first, source_present = 1), or one row with source_present = 0
// and empty fields when none passed the threshold:
//     t_s,peak,source_present,azimuth_rad,elevation_rad,cone_angle_rad,
//     mirror_azimuth_rad,mirror_elevation_rad,statistic,threshold,power_db
// t_s is the frame's centre. A field the array cannot observe is empty: azimuth and
// elevation for a line (its cone angle instead), the cone angle for other shapes, the mirror
// unless a planar array's side was not stated. Angles in the array file's frame (azimuth
// atan2(y, x), elevation from the x-y plane towards +z). No tracking: peaks carry no identity
// from frame to frame (issue 18's next step).
//
// Memory: one read chunk plus the framer's buffer, whatever the file length. The WAV
// header's sample rate wins over the array file's (a difference is reported through
// `on_warning`). Channel count must equal the array's sensor count.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "engine/core/status.h"
#include "engine/core/types.h"
#include "engine/doa/srp_phat.h"

namespace localizer::io {

struct DoaJob {
  std::vector<std::string> wav_paths;
  std::string array_source = "array.json";  // names the array in messages
  std::vector<engine::Vec3> sensors_m;
  double sound_speed_mps = 343.0;
  std::optional<double> array_sample_rate_hz;  // from the array file, checked against the WAV
  engine::SrpOptions srp;                      // sample_rate_hz is taken from the WAV header
  int hop_samples = 256;                       // in [1, srp.frame_samples]
  std::string csv_path;                        // required
};

struct DoaSummary {
  engine::ArrayShape shape = engine::ArrayShape::kVolumetric;
  double sample_rate_hz = 0.0;
  int64_t frames = 0;
  int64_t frames_with_source = 0;
  int64_t peaks = 0;
  double wall_s = 0.0;  // framing and analysis, excluding setup
};

// INVALID_ARGUMENT naming the file or option; NOT_FOUND for a missing file.
StatusOr<DoaSummary> RunDoa(const DoaJob& job, const std::function<void(const std::string&)>& on_warning = nullptr);

}  // namespace localizer::io
