// The XAV deployment's own files, read for what they say (Mouy et al. 2023; the folder
// ../shared/data/xav-large-array): instead of constants, the hydrophone CSV's neighbours
// give the array its sound speed, reference channel, sample rate and water column.
//
//   localization_config*.yaml   ENVIRONMENT.sound_speed_mps, TDOA.ref_channel (the index of
//                               the reference hydrophone, 0-based as the CSV's array_channel)
//   deployment_info.csv         per audio channel: sampling_frequency (Hz), hydrophone_depth
//                               (m below the surface), location_water_depth (m),
//                               location_lat / location_lon (degrees)
// YAML through yaml-cpp (Debian: libyaml-cpp-dev).
#pragma once

#include <string>
#include <vector>

#include "engine/core/status.h"

namespace localizer::io {

struct XavLocalizationConfig {
  double sound_speed_mps = 0.0;
  int reference_sensor = 0;
};
// INVALID_ARGUMENT naming the file and the key when a key is missing or out of range
// (sound speed in (0, 1e4) m/s, ref_channel >= 0); NOT_FOUND when the file cannot be read.
StatusOr<XavLocalizationConfig> ReadXavLocalizationYaml(const std::string& path);

struct XavDeployment {
  double sample_rate_hz = 0.0;               // one value for every channel
  double water_depth_m = 0.0;                // one value for every channel
  std::vector<double> hydrophone_depth_m;    // by audio_channel_number, 0 .. N-1
  double latitude_deg = 0.0, longitude_deg = 0.0;
};
// Every channel 0 .. N-1 once; sample rate and water depth positive and equal on all rows.
StatusOr<XavDeployment> ReadXavDeploymentCsv(const std::string& path);

// The one file in `dir` whose name starts with `prefix` and ends with `suffix`: NOT_FOUND
// naming the pattern when there is none, INVALID_ARGUMENT when there are several.
StatusOr<std::string> FindOneFile(const std::string& dir, const std::string& prefix, const std::string& suffix);

}  // namespace localizer::io
