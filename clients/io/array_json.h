// `array.json`: the sensor array a recording was made with.
//
//   {
//     "sound_speed_mps": 1500.0,               required, finite, > 0
//     "sample_rate_hz": 11025,                 optional, finite, > 0 (a WAV header wins)
//     "sensors_m": [[x, y, z], ...],           required, metres, one row per sensor/channel
//     "reference_sensor": 0,                   optional integer, default 0
//     "band_hz": [300, 3000],                  optional processing hint: the source's band,
//                                              used as the GCC band when none is given
//     "bounds_min_m": [x, y, z],               optional physical bounds on the source, metres:
//     "bounds_max_m": [x, y, z],               per axis a number, or null (or "-inf" for a
//                                              min, "inf" for a max) for an open side;
//                                              default open everywhere; min < max per axis
//     "surface_z_m": 7.03,                     optional, a water column with z up: the
//     "bottom_z_m": -0.97,                     surface is the upper z bound, the bottom the
//                                              lower (each excludes the same side of
//                                              bounds_max_m / bounds_min_m)
//     "localization": "auto",                  optional: "auto" (default), "position"
//                                              (track, locate) or "direction"
//                                              (localizer-cli doa); a file that says one is
//                                              refused by the other
//     "source_side": {"normal": [0, 0, 1]},    optional: the sources lie where
//                                              (p - centroid) . normal > 0 (a planar array's
//                                              side; a linear one's within source_plane)
//     "source_plane": {"point_m": [0, 0, 1.5], optional, a linear array's positions: the
//                      "normal": [0, 0, 1]},   plane that holds the array and the sources
//     "max_sources": 4,                        optional: sources per frame, 1..16 (unset: 4 for
//                                              directions, one tracked source for a volumetric
//                                              array's positions; 2 or more: that many, each
//                                              with its position)
//     "geodetic_origin": {"latitude_deg": 49.49,  optional: where the array frame's origin is
//       "longitude_deg": -124.66,               (WGS84) and heading_deg, the bearing of its
//       "altitude_m": 0, "heading_deg": 30}     +y axis from true north (geodetic.h); for
//                                              --format geojson
//     "session": {"particles": 1024,           optional: the session's tracking settings under
//                 "filter": "ekf", ...}         localizer.engine's option names, read alike by
//                                              localizer-cli (a flag wins), localizer.engine and
//                                              the Python gRPC client (session_file.h)
//   }
// Array + "session" is the session file: one file that describes a whole session.
// Positions from a planar array need source_side; from a linear one, source_plane and
// source_side (engine/pipeline/session_config.h).
//
// Reading also checks the geometry against its use (ArrayUse), so a bad array fails at load
// time with the engine's message, naming the file: for positions it builds an
// engine::ArrayGeometry (fewer than 4 sensors, coplanar or coincident sensors fail); for
// directions any array of 2 or more distinct sensors is accepted (engine/doa/array_shape.h). Unknown fields are
// rejected so that a misspelt optional field
// ("reference_sensr") cannot be silently ignored. Every error names the source and field.
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "clients/io/geodetic.h"
#include "clients/io/session_file.h"
#include "engine/core/status.h"
#include "engine/core/types.h"

namespace localizer::io {

struct ArrayFile {
  std::vector<engine::Vec3> sensors_m;
  double sound_speed_mps = 0.0;
  std::optional<double> sample_rate_hz;
  int reference_sensor = 0;
  std::optional<std::pair<double, double>> band_hz;  // (low, high), 0 <= low < high
  // Physical bounds on the source (engine::AudioSessionConfig::bounds_min_m/max_m): +-infinity
  // on an open side, the default. surface_z_m / bottom_z_m land in bounds_max_m.z() /
  // bounds_min_m.z().
  engine::Vec3 bounds_min_m = engine::Vec3::Constant(-std::numeric_limits<double>::infinity());
  engine::Vec3 bounds_max_m = engine::Vec3::Constant(std::numeric_limits<double>::infinity());
  bool has_bounds() const { return bounds_min_m.array().isFinite().any() || bounds_max_m.array().isFinite().any(); }
  // Direction finding (above); in engine::Localization's order.
  enum class Localization { kAuto, kPosition, kDirection };
  Localization localization = Localization::kAuto;
  std::optional<engine::Vec3> source_side_normal;  // finite, not zero
  std::optional<int> max_sources;                  // 1..16
  struct Plane {
    engine::Vec3 point_m = engine::Vec3::Zero();
    engine::Vec3 normal = engine::Vec3::UnitZ();  // finite, not zero
  };
  std::optional<Plane> source_plane;
  std::optional<GeodeticOrigin> geodetic_origin;  // geodetic.h
  SessionSettings session;                        // "session" (session_file.h); empty if absent
};

// What the array will be used for, which decides the geometry it needs.
enum class ArrayUse {
  kPosition,   // 3-D localisation (track, locate, simulate): 4 or more sensors, not coplanar
  kDirection,  // direction of arrival (doa): 2 or more distinct sensors, any shape
  kAuto,       // as the file's localization says (track): any array of 2 or more distinct
               // sensors; the session decides what it gives (and names a missing constraint)
};

// `source` names the text in messages (usually its path).
StatusOr<ArrayFile> ParseArrayJson(const std::string& text, const std::string& source,
                                   ArrayUse use = ArrayUse::kPosition);
StatusOr<ArrayFile> ReadArrayJson(const std::string& path, ArrayUse use = ArrayUse::kPosition);
Status WriteArrayJson(const std::string& path, const ArrayFile& array);

// Reads an array description by file type: `.csv` is the XAV hydrophone configuration
// (see xav_array.h), anything else array.json.
StatusOr<ArrayFile> ReadArrayFile(const std::string& path, ArrayUse use = ArrayUse::kPosition);

}  // namespace localizer::io
