// The XAV hydrophone array of Mouy et al. (2023) as the authors describe it in
// `hydrophones_config_07-HI.csv`: columns name,x,y,z,... (metres, array frame) and
// file_name_root ("AMAR173.1.") naming each hydrophone's recording; one row per hydrophone
// in channel order. The authors' localisation config gives the rest: sound speed
// 1484 m/s and reference channel 3 (the hydrophone near the array centre). The recordings
// are 32 kHz (deployment_info.csv).
//
// The water column, from deployment_info.csv: the water is 8 m deep (location_water_depth)
// and each hydrophone's depth is 7.03 m - z (hydrophone_depth, to the centimetre), so z
// points up, the surface is z = 7.03 m and the bottom z = 7.03 - 8 = -0.97 m (the lowest
// hydrophones, z = -0.671, sit 0.3 m above it). Both are the array file's bounds
// (bounds_max_m.z / bounds_min_m.z); x and y are open. The depths are the deployment's
// nominal values: tide moves the surface by a few metres, the bottom not at all.
#pragma once

#include <string>
#include <vector>

#include "clients/io/array_json.h"
#include "engine/core/status.h"

namespace localizer::io {

inline constexpr double kXavSoundSpeedMps = 1484.0;
inline constexpr int kXavReferenceSensor = 3;
inline constexpr double kXavSampleRateHz = 32000.0;
inline constexpr double kXavWaterDepthM = 8.0;
inline constexpr double kXavSurfaceZM = 7.03;                            // array frame, z up
inline constexpr double kXavBottomZM = kXavSurfaceZM - kXavWaterDepthM;  // -0.97

struct XavArray {
  ArrayFile array;                           // sensors, c = 1484 m/s, reference 3, 32 kHz, the water column as bounds
  std::vector<std::string> file_name_roots;  // per hydrophone, e.g. "AMAR173.1."
};

StatusOr<XavArray> ReadXavHydrophoneCsv(const std::string& path);

// For each root, the one `<root>*.wav` in `dir`, in hydrophone order; NOT_FOUND naming the
// root when there is none, INVALID_ARGUMENT when there are several.
StatusOr<std::vector<std::string>> FindXavRecordings(const std::string& dir, const std::vector<std::string>& roots);

}  // namespace localizer::io
