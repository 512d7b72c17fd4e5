#include "clients/io/array_json.h"

#include <climits>
#include <cmath>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "clients/io/json_fields.h"
#include "clients/io/xav_array.h"
#include "engine/array/array_geometry.h"
#include "engine/doa/array_shape.h"

namespace localizer::io {

namespace {

using nlohmann::json;

const std::set<std::string> kKnownFields = {"sound_speed_mps", "sample_rate_hz",  "sensors_m",    "reference_sensor",
                                            "band_hz",         "bounds_min_m",    "bounds_max_m", "surface_z_m",
                                            "bottom_z_m",      "localization",    "source_side",  "max_sources",
                                            "source_plane",    "geodetic_origin", "session"};
const char* const kLocalizationNames[] = {"auto", "position", "direction"};  // ArrayFile::Localization order

StatusOr<std::vector<engine::Vec3>> ParseSensors(const json& rows, const std::string& source) {
  if (!rows.is_array()) {
    return InvalidArgument(source + ": sensors_m must be an array of [x, y, z] rows");
  }
  std::vector<engine::Vec3> sensors_m;
  for (size_t k = 0; k < rows.size(); ++k) {
    const std::string row_name = "sensors_m[" + std::to_string(k) + "]";
    if (!rows[k].is_array() || rows[k].size() != 3) {
      return InvalidArgument(source + ": " + row_name + " is " + rows[k].dump() + ", not [x, y, z]");
    }
    engine::Vec3 position_m;
    for (int axis = 0; axis < 3; ++axis) {
      auto x = FiniteNumber(rows[k][axis], source, row_name + "[" + std::to_string(axis) + "]");
      if (!x.ok()) return x.status();
      position_m[axis] = *x;
    }
    sensors_m.push_back(position_m);
  }
  return sensors_m;
}

StatusOr<int> ParseReference(const json& value, const std::string& source) {
  if (!value.is_number_integer()) {
    return InvalidArgument(source + ": reference_sensor is " + value.dump() + ", not an integer");
  }
  // Range-checked before the cast: 4294967297 must not become sensor 1.
  const bool in_range = value.is_number_unsigned() ? value.get<uint64_t>() <= uint64_t{INT_MAX}
                                                   : value.get<int64_t>() >= 0 && value.get<int64_t>() <= INT_MAX;
  if (!in_range) return InvalidArgument(source + ": reference_sensor is " + value.dump() + ", not a sensor index");
  return static_cast<int>(value.get<int64_t>());
}

// One side of the bounds box: per axis a finite number, or null / the string naming its
// open direction ("-inf" for a min, "inf" for a max).
Status ParseBoundsSide(const json& row, const std::string& source, const std::string& field, bool is_min,
                       engine::Vec3* out) {
  if (!row.is_array() || row.size() != 3) {
    return InvalidArgument(source + ": " + field + " is " + row.dump() +
                           ", not [x, y, z] (a number or null per axis; null = open)");
  }
  const double open = is_min ? -std::numeric_limits<double>::infinity() : std::numeric_limits<double>::infinity();
  for (int axis = 0; axis < 3; ++axis) {
    const json& v = row[axis];
    const std::string name = field + "[" + std::to_string(axis) + "]";
    if (v.is_null() || (v.is_string() && v.get<std::string>() == (is_min ? "-inf" : "inf"))) {
      (*out)[axis] = open;
      continue;
    }
    auto x = FiniteNumber(v, source, name);
    if (!x.ok()) {
      return InvalidArgument(source + ": " + name + " is " + v.dump() + "; must be a finite number, or null or \"" +
                             (is_min ? "-inf" : "inf") + "\" for an open side");
    }
    (*out)[axis] = *x;
  }
  return Status::Ok();
}

Status ParseBounds(const json& root, const std::string& source, ArrayFile* array) {
  if (root.contains("bounds_min_m")) {
    LOCALIZER_RETURN_IF_ERROR(
        ParseBoundsSide(root["bounds_min_m"], source, "bounds_min_m", true, &array->bounds_min_m));
  }
  if (root.contains("bounds_max_m")) {
    LOCALIZER_RETURN_IF_ERROR(
        ParseBoundsSide(root["bounds_max_m"], source, "bounds_max_m", false, &array->bounds_max_m));
  }
  if (root.contains("surface_z_m")) {
    auto z = FiniteNumber(root["surface_z_m"], source, "surface_z_m");
    if (!z.ok()) return z.status();
    if (std::isfinite(array->bounds_max_m.z())) {
      return InvalidArgument(source + ": surface_z_m and bounds_max_m[2] both give the upper z bound; keep one");
    }
    array->bounds_max_m.z() = *z;
  }
  if (root.contains("bottom_z_m")) {
    auto z = FiniteNumber(root["bottom_z_m"], source, "bottom_z_m");
    if (!z.ok()) return z.status();
    if (std::isfinite(array->bounds_min_m.z())) {
      return InvalidArgument(source + ": bottom_z_m and bounds_min_m[2] both give the lower z bound; keep one");
    }
    array->bounds_min_m.z() = *z;
  }
  const char* axes = "xyz";
  for (int axis = 0; axis < 3; ++axis) {
    if (!(array->bounds_min_m[axis] < array->bounds_max_m[axis])) {
      return InvalidArgument(source + ": the " + std::string(1, axes[axis]) + " bounds are empty: min " +
                             std::to_string(array->bounds_min_m[axis]) + " must be below max " +
                             std::to_string(array->bounds_max_m[axis]) +
                             (axis == 2 ? " (bottom_z_m below surface_z_m, with z up)" : ""));
    }
  }
  return Status::Ok();
}

// "geodetic_origin": {"latitude_deg", "longitude_deg", "altitude_m" (optional, 0),
// "heading_deg" (optional)} (geodetic.h).
Status ParseGeodeticOrigin(const json& root, const std::string& source, ArrayFile* array) {
  if (!root.contains("geodetic_origin")) return Status::Ok();
  const json& g = root["geodetic_origin"];
  const std::set<std::string> known = {"latitude_deg", "longitude_deg", "altitude_m", "heading_deg"};
  if (!g.is_object() || !g.contains("latitude_deg") || !g.contains("longitude_deg")) {
    return InvalidArgument(source +
                           ": geodetic_origin must be {\"latitude_deg\": ..., \"longitude_deg\": ..., "
                           "\"altitude_m\": ... (optional), \"heading_deg\": ... (optional)}");
  }
  for (const auto& item : g.items()) {
    if (!known.contains(item.key())) {
      return InvalidArgument(source + ": geodetic_origin: unknown field \"" + item.key() +
                             "\" (known: latitude_deg, longitude_deg, altitude_m, heading_deg)");
    }
  }
  GeodeticOrigin origin;
  auto lat = FiniteNumber(g["latitude_deg"], source, "geodetic_origin.latitude_deg");
  if (!lat.ok()) return lat.status();
  auto lon = FiniteNumber(g["longitude_deg"], source, "geodetic_origin.longitude_deg");
  if (!lon.ok()) return lon.status();
  if (!(std::abs(*lat) <= 90.0) || !(std::abs(*lon) <= 180.0)) {
    return InvalidArgument(source +
                           ": geodetic_origin: latitude_deg must be in [-90, 90] and longitude_deg in "
                           "[-180, 180]");
  }
  origin.latitude_deg = *lat;
  origin.longitude_deg = *lon;
  if (g.contains("altitude_m")) {
    auto alt = FiniteNumber(g["altitude_m"], source, "geodetic_origin.altitude_m");
    if (!alt.ok()) return alt.status();
    origin.altitude_m = *alt;
  }
  if (g.contains("heading_deg")) {
    auto heading = FiniteNumber(g["heading_deg"], source, "geodetic_origin.heading_deg");
    if (!heading.ok()) return heading.status();
    origin.heading_deg = *heading;
  }
  array->geodetic_origin = origin;
  return Status::Ok();
}

Status CheckFields(const json& root, const std::string& source) {
  if (!root.is_object()) return InvalidArgument(source + ": top level must be a JSON object");
  for (const auto& item : root.items()) {
    if (!kKnownFields.contains(item.key())) {
      return InvalidArgument(source + ": unknown field \"" + item.key() +
                             "\" (known: sound_speed_mps, sample_rate_hz, sensors_m, "
                             "reference_sensor, band_hz, bounds_min_m, bounds_max_m, surface_z_m, "
                             "bottom_z_m, localization, source_side, max_sources, source_plane, geodetic_origin, "
                             "session)");
    }
  }
  for (const char* required : {"sound_speed_mps", "sensors_m"}) {
    if (!root.contains(required)) {
      return InvalidArgument(source + ": missing required field " + required);
    }
  }
  return Status::Ok();
}

Status ParseDirectionFields(const json& root, const std::string& source, ArrayFile* array) {
  if (root.contains("localization")) {
    const json& v = root["localization"];
    bool known = false;
    for (int i = 0; i < 3 && v.is_string(); ++i) {
      if (v.get<std::string>() == kLocalizationNames[i]) {
        array->localization = static_cast<ArrayFile::Localization>(i);
        known = true;
      }
    }
    if (!known) {
      return InvalidArgument(source + ": localization must be \"auto\", \"position\" or \"direction\", got " +
                             v.dump());
    }
  }
  if (root.contains("source_side")) {
    const json& side = root["source_side"];
    if (!side.is_object() || side.size() != 1 || !side.contains("normal")) {
      return InvalidArgument(source + ": source_side must be {\"normal\": [x, y, z]}");
    }
    auto normal = FiniteVector(side["normal"], source, "source_side.normal");
    if (!normal.ok()) return normal.status();
    if (!(normal->norm() > 0.0)) return InvalidArgument(source + ": source_side.normal must not be zero");
    array->source_side_normal = *normal;
  }
  if (root.contains("source_plane")) {
    const json& plane = root["source_plane"];
    if (!plane.is_object() || plane.size() != 2 || !plane.contains("point_m") || !plane.contains("normal")) {
      return InvalidArgument(source + ": source_plane must be {\"point_m\": [x, y, z], \"normal\": [nx, ny, nz]}");
    }
    auto point = FiniteVector(plane["point_m"], source, "source_plane.point_m");
    if (!point.ok()) return point.status();
    auto normal = FiniteVector(plane["normal"], source, "source_plane.normal");
    if (!normal.ok()) return normal.status();
    if (!(normal->norm() > 0.0)) return InvalidArgument(source + ": source_plane.normal must not be zero");
    array->source_plane = ArrayFile::Plane{*point, *normal};
  }
  if (root.contains("max_sources")) {
    const json& v = root["max_sources"];
    if (!v.is_number_integer() || v.get<int64_t>() < 1 || v.get<int64_t>() > 16) {
      return InvalidArgument(source + ": max_sources must be an integer in [1, 16], got " + v.dump());
    }
    array->max_sources = static_cast<int>(v.get<int64_t>());
  }
  return Status::Ok();
}

StatusOr<ArrayFile> FromJson(const json& root, const std::string& source) {
  LOCALIZER_RETURN_IF_ERROR(CheckFields(root, source));
  ArrayFile array;
  auto c = PositiveNumber(root["sound_speed_mps"], source, "sound_speed_mps");
  if (!c.ok()) return c.status();
  array.sound_speed_mps = *c;
  if (root.contains("sample_rate_hz")) {
    auto rate = PositiveNumber(root["sample_rate_hz"], source, "sample_rate_hz");
    if (!rate.ok()) return rate.status();
    array.sample_rate_hz = *rate;
  }
  auto sensors = ParseSensors(root["sensors_m"], source);
  if (!sensors.ok()) return sensors.status();
  array.sensors_m = std::move(*sensors);
  if (root.contains("reference_sensor")) {
    auto reference = ParseReference(root["reference_sensor"], source);
    if (!reference.ok()) return reference.status();
    array.reference_sensor = *reference;
  }
  if (root.contains("band_hz")) {
    const json& band = root["band_hz"];
    if (!band.is_array() || band.size() != 2 || !band[0].is_number() || !band[1].is_number() ||
        !(band[0].get<double>() >= 0.0) || !(band[1].get<double>() > band[0].get<double>())) {
      return InvalidArgument(source + ": band_hz must be [low, high] with 0 <= low < high, got " + band.dump());
    }
    array.band_hz = std::make_pair(band[0].get<double>(), band[1].get<double>());
  }
  LOCALIZER_RETURN_IF_ERROR(ParseBounds(root, source, &array));
  LOCALIZER_RETURN_IF_ERROR(ParseDirectionFields(root, source, &array));
  LOCALIZER_RETURN_IF_ERROR(ParseGeodeticOrigin(root, source, &array));
  if (root.contains("session"))
    LOCALIZER_RETURN_IF_ERROR(ParseSessionSettings(root["session"], source, &array.session));
  return array;
}

}  // namespace

StatusOr<ArrayFile> ParseArrayJson(const std::string& text, const std::string& source, ArrayUse use) {
  json root;
  try {
    root = json::parse(text);
  } catch (const json::exception& e) {
    return InvalidArgument(source + ": not valid JSON: " + e.what());
  }
  auto array = FromJson(root, source);
  if (!array.ok()) return array;
  const bool wants_direction = array->localization == ArrayFile::Localization::kDirection;
  if (use != ArrayUse::kAuto && wants_direction != (use == ArrayUse::kDirection) &&
      array->localization != ArrayFile::Localization::kAuto) {
    return InvalidArgument(source + (wants_direction
                                         ? ": localization is \"direction\": use localizer-cli doa (or \"auto\")"
                                         : ": localization is \"position\": localizer-cli doa reports directions"));
  }
  // Validate the geometry now so that a bad array fails where the file is named.
  // (kAuto: the session decides what the shape gives, and says what is missing.)
  if (use == ArrayUse::kDirection || use == ArrayUse::kAuto) {
    auto shape = engine::ClassifyArray(array->sensors_m);
    if (!shape.ok()) return InvalidArgument(source + ": " + shape.status().message());
    if (array->reference_sensor >= static_cast<int>(array->sensors_m.size()))
      return InvalidArgument(source + ": reference_sensor is not one of the sensors");
    return array;
  }
  auto geometry = engine::ArrayGeometry::Create(array->sensors_m, array->sound_speed_mps, array->reference_sensor);
  if (!geometry.ok()) return InvalidArgument(source + ": " + geometry.status().message());
  return array;
}

StatusOr<ArrayFile> ReadArrayJson(const std::string& path, ArrayUse use) {
  std::ifstream in(path);
  if (!in) return NotFound(path + ": cannot open");
  std::ostringstream text;
  text << in.rdbuf();
  return ParseArrayJson(text.str(), path, use);
}

Status WriteArrayJson(const std::string& path, const ArrayFile& array) {
  json root;
  root["sound_speed_mps"] = array.sound_speed_mps;
  if (array.sample_rate_hz) root["sample_rate_hz"] = *array.sample_rate_hz;
  root["reference_sensor"] = array.reference_sensor;
  if (array.band_hz) root["band_hz"] = {array.band_hz->first, array.band_hz->second};
  if (array.has_bounds()) {  // open sides as null
    const auto side = [](const engine::Vec3& v) {
      json row = json::array();
      for (int axis = 0; axis < 3; ++axis) row.push_back(std::isfinite(v[axis]) ? json(v[axis]) : json(nullptr));
      return row;
    };
    root["bounds_min_m"] = side(array.bounds_min_m);
    root["bounds_max_m"] = side(array.bounds_max_m);
  }
  if (array.localization != ArrayFile::Localization::kAuto)
    root["localization"] = kLocalizationNames[static_cast<int>(array.localization)];
  if (const auto& n = array.source_side_normal) root["source_side"] = {{"normal", {n->x(), n->y(), n->z()}}};
  if (array.max_sources) root["max_sources"] = *array.max_sources;
  if (const auto& plane = array.source_plane) {
    root["source_plane"] = {{"point_m", {plane->point_m.x(), plane->point_m.y(), plane->point_m.z()}},
                            {"normal", {plane->normal.x(), plane->normal.y(), plane->normal.z()}}};
  }
  if (const auto& g = array.geodetic_origin) {
    root["geodetic_origin"] = {
        {"latitude_deg", g->latitude_deg}, {"longitude_deg", g->longitude_deg}, {"altitude_m", g->altitude_m}};
    if (g->heading_deg) root["geodetic_origin"]["heading_deg"] = *g->heading_deg;
  }
  if (!array.session.empty()) root["session"] = SessionSettingsToJson(array.session);
  json rows = json::array();
  for (const engine::Vec3& m : array.sensors_m) rows.push_back({m.x(), m.y(), m.z()});
  root["sensors_m"] = std::move(rows);
  std::ofstream out(path);
  if (!out) return InvalidArgument(path + ": cannot open for writing");
  out << root.dump(2) << "\n";
  out.close();
  if (!out) return InvalidArgument(path + ": write failed");
  return Status::Ok();
}

StatusOr<ArrayFile> ReadArrayFile(const std::string& path, ArrayUse use) {
  if (path.size() >= 4 && path.compare(path.size() - 4, 4, ".csv") == 0) {
    auto xav = ReadXavHydrophoneCsv(path);
    if (!xav.ok()) return xav.status();
    return xav->array;  // six hydrophones in 3-D: good for either use
  }
  return ReadArrayJson(path, use);
}

}  // namespace localizer::io
