// The XAV hydrophone array of Mouy et al. (2023) as the authors describe it in
// `hydrophones_config_07-HI.csv`: columns name,x,y,z,... (metres, array frame, z up),
// array_channel (optional; else the row order) and file_name_root ("AMAR173.1.") naming each
// hydrophone's recording; one row per hydrophone. The rest comes from the deployment's own
// files beside it (xav_config.h), read for what they say, not assumed:
//   localization_config*.yaml: sound speed (1484 m/s there) and reference channel (3, the
//     hydrophone near the array centre);
//   deployment_info.csv: sample rate (32 kHz), water depth (8 m) and each hydrophone's depth.
// The water column: each hydrophone's depth is surface_z - z, so the surface is the median of
// depth + z over the hydrophones (7.03 m in the array frame there) and the bottom lies the
// water depth below it (-0.97 m); both become the array file's bounds (bounds_max_m.z /
// bounds_min_m.z), x and y open. The sheet's latitude and longitude become the array's
// geodetic origin (its altitude -surface_z_m: sea level taken as the ellipsoid, a few tens of
// metres off, which only shifts GeoJSON altitudes); no heading, since the sheet gives none. The depths are the deployment's nominal values: tide moves
// the surface by a few metres, the bottom not at all. A CSV without those two files beside it
// is refused, naming what is missing (write an array.json for other arrays).
#pragma once

#include <string>
#include <vector>

#include "clients/io/array_json.h"
#include "engine/core/status.h"

namespace localizer::io {

struct XavArray {
  ArrayFile array;  // sensors, sound speed, reference, sample rate, the water column as bounds
  std::vector<std::string> file_name_roots;  // per hydrophone, e.g. "AMAR173.1."

  double water_depth_m = 0.0;
  double surface_z_m = 0.0;  // array frame, z up
};

StatusOr<XavArray> ReadXavHydrophoneCsv(const std::string& path);

// For each root, the one `<root>*.wav` in `dir`, in hydrophone order; NOT_FOUND naming the
// root when there is none, INVALID_ARGUMENT when there are several.
StatusOr<std::vector<std::string>> FindXavRecordings(const std::string& dir, const std::vector<std::string>& roots);

}  // namespace localizer::io
