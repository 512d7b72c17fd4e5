#include "clients/io/room_scene_files.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "clients/io/csv_table.h"
#include "clients/io/json_fields.h"
#include "clients/io/wav_io.h"
#include "engine/doa/array_shape.h"

namespace localizer::io {
namespace {

using nlohmann::json;

Status CheckKnown(const json& object, const std::set<std::string>& known, const std::string& source,
                  const std::string& where) {
  if (!object.is_object()) return InvalidArgument(source + ": " + where + " must be a JSON object");
  for (const auto& item : object.items()) {
    if (!known.contains(item.key())) {
      std::string names;
      for (const std::string& k : known) names += (names.empty() ? "" : ", ") + k;
      return InvalidArgument(source + ": unknown field \"" + item.key() + "\" in " + where + " (known: " + names + ")");
    }
  }
  return Status::Ok();
}

// [a, b] with finite numbers.
StatusOr<std::pair<double, double>> Range(const json& value, const std::string& source, const std::string& field) {
  if (!value.is_array() || value.size() != 2) {
    return InvalidArgument(source + ": " + field + " must be [low, high], got " + value.dump());
  }
  auto a = FiniteNumber(value[0], source, field);
  if (!a.ok()) return a.status();
  auto b = FiniteNumber(value[1], source, field);
  if (!b.ok()) return b.status();
  return std::make_pair(*a, *b);
}

StatusOr<engine::RoomSceneSource> ParseSource(const json& s, const std::string& source, const std::string& where,
                                              double sample_rate_hz) {
  LOCALIZER_RETURN_IF_ERROR(CheckKnown(s,
                                       {"position_m", "signal", "band_hz", "level_db", "on_s", "off_s", "start_s",
                                        "stop_s"},
                                       source, where));
  engine::RoomSceneSource out;
  out.band_high_hz = std::min(out.band_high_hz, 0.5 * sample_rate_hz);
  if (!s.contains("position_m")) return InvalidArgument(source + ": " + where + " needs position_m");
  auto p = FiniteVector(s["position_m"], source, where + ".position_m");
  if (!p.ok()) return p.status();
  out.position_m = *p;
  if (s.contains("signal")) {
    if (!s["signal"].is_string()) return InvalidArgument(source + ": " + where + ".signal must be a string");
    auto kind = engine::ParseRoomSignal(s["signal"].get<std::string>(), source + ": " + where + ".signal");
    if (!kind.ok()) return kind.status();
    out.signal = *kind;
  }
  if (s.contains("band_hz")) {
    auto band = Range(s["band_hz"], source, where + ".band_hz");
    if (!band.ok()) return band.status();
    std::tie(out.band_low_hz, out.band_high_hz) = *band;
  }
  for (const auto& [name, target] : {std::pair<const char*, double*>{"level_db", &out.level_db},
                                     {"start_s", &out.start_s}, {"stop_s", &out.stop_s}}) {
    if (!s.contains(name)) continue;
    auto v = FiniteNumber(s[name], source, where + "." + name);
    if (!v.ok()) return v.status();
    *target = *v;
  }
  for (const auto& [name, low, high] : {std::tuple<const char*, double*, double*>{"on_s", &out.on_min_s, &out.on_max_s},
                                        {"off_s", &out.off_min_s, &out.off_max_s}}) {
    if (!s.contains(name)) continue;
    auto v = Range(s[name], source, where + "." + name);
    if (!v.ok()) return v.status();
    std::tie(*low, *high) = *v;
  }
  return out;
}

}  // namespace

StatusOr<RoomSceneFile> ParseRoomSceneJson(const std::string& text, const std::string& source) {
  json root;
  try {
    root = json::parse(text);
  } catch (const json::exception& e) {
    return InvalidArgument(source + ": not valid JSON: " + e.what());
  }
  LOCALIZER_RETURN_IF_ERROR(CheckKnown(
      root, {"room", "array_position_m", "sample_rate_hz", "duration_s", "noise_db", "sources"}, source, "the scene"));
  RoomSceneFile out;
  engine::RoomScene& scene = out.scene;
  if (!root.contains("room")) return InvalidArgument(source + ": missing required field room");
  LOCALIZER_RETURN_IF_ERROR(CheckKnown(root["room"], {"size_m", "rt60_s"}, source, "room"));
  if (!root["room"].contains("size_m")) return InvalidArgument(source + ": room needs size_m");
  auto size = FiniteVector(root["room"]["size_m"], source, "room.size_m");
  if (!size.ok()) return size.status();
  scene.room.size_m = *size;
  if (root["room"].contains("rt60_s")) {
    auto rt60 = FiniteNumber(root["room"]["rt60_s"], source, "room.rt60_s");
    if (!rt60.ok()) return rt60.status();
    scene.room.rt60_s = *rt60;
  }
  if (root.contains("array_position_m")) {
    auto p = FiniteVector(root["array_position_m"], source, "array_position_m");
    if (!p.ok()) return p.status();
    out.array_position_m = *p;
  }
  for (const auto& [name, target] : {std::pair<const char*, double*>{"sample_rate_hz", &scene.sample_rate_hz},
                                     {"duration_s", &scene.duration_s}, {"noise_db", &scene.noise_db}}) {
    if (!root.contains(name)) continue;
    auto v = FiniteNumber(root[name], source, name);
    if (!v.ok()) return v.status();
    *target = *v;
  }
  if (!root.contains("sources") || !root["sources"].is_array()) {
    return InvalidArgument(source + ": sources must be a list of sources");
  }
  if (root["sources"].size() > 16) {
    return InvalidArgument(source + ": sources lists " + std::to_string(root["sources"].size()) + "; at most 16");
  }
  for (size_t i = 0; i < root["sources"].size(); ++i) {
    auto s = ParseSource(root["sources"][i], source, "sources[" + std::to_string(i) + "]", scene.sample_rate_hz);
    if (!s.ok()) return s.status();
    scene.sources.push_back(*s);
  }
  return out;
}

StatusOr<RoomSceneFile> ReadRoomSceneJson(const std::string& path) {
  std::ifstream in(path);
  if (!in) return InvalidArgument(path + ": cannot open for reading");
  std::ostringstream text;
  text << in.rdbuf();
  return ParseRoomSceneJson(text.str(), path);
}

StatusOr<RoomSimulationFiles> SimulateRoomScene(const RoomSceneFile& file, const ArrayFile& array, uint64_t seed,
                                                std::optional<double> duration_s, const std::string& dir) {
  engine::RoomScene scene = file.scene;
  scene.room.sound_speed_mps = array.sound_speed_mps;
  if (duration_s) scene.duration_s = *duration_s;
  std::vector<engine::Vec3> sensors_m = array.sensors_m;
  for (engine::Vec3& s : sensors_m) s += file.array_position_m;
  auto shape = engine::ClassifyArray(sensors_m);
  if (!shape.ok()) return shape.status();
  auto rendered = engine::RenderRoomScene(scene, sensors_m, seed);
  if (!rendered.ok()) return rendered.status();

  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (error) return InvalidArgument(dir + ": cannot create directory: " + error.message());
  const std::filesystem::path base(dir);
  RoomSimulationFiles files{(base / "signals.wav").string(), (base / "array.json").string(),
                            (base / "sources.csv").string(), (base / "sounding.csv").string(),
                            rendered->samples_per_channel};
  LOCALIZER_RETURN_IF_ERROR(WriteWavFloat(files.wav_path, scene.sample_rate_hz, static_cast<int>(sensors_m.size()),
                                          rendered->samples_per_channel, rendered->samples.data()));
  ArrayFile moved = array;
  moved.sensors_m = sensors_m;
  moved.sample_rate_hz = scene.sample_rate_hz;
  if (moved.source_plane) moved.source_plane->point_m += file.array_position_m;
  LOCALIZER_RETURN_IF_ERROR(WriteArrayJson(files.array_path, moved));

  std::ofstream sources(files.sources_path);
  sources << "source,signal,x_m,y_m,z_m,range_m,azimuth_rad,elevation_rad,cone_angle_rad\n";
  std::vector<double> travel_s;
  for (size_t i = 0; i < scene.sources.size(); ++i) {
    const engine::RoomSceneSource& s = scene.sources[i];
    const engine::Vec3 sight_m = s.position_m - shape->centroid_m;
    const double range_m = sight_m.norm();
    const engine::Vec3 u = sight_m / range_m;
    const double cone =
        shape->shape == engine::ArrayShape::kLinear ? engine::ConeAngleRad(u, shape->axis) : std::nan("");
    std::string row = std::to_string(i) + ',' + engine::RoomSignalName(s.signal);
    for (double v : {s.position_m.x(), s.position_m.y(), s.position_m.z(), range_m, engine::AzimuthRad(u),
                     engine::ElevationRad(u), cone}) {
      AppendField(v, &row);
    }
    sources << row << '\n';
    travel_s.push_back(range_m / scene.room.sound_speed_mps);
  }
  if (!sources.flush()) return InvalidArgument(files.sources_path + ": write failed");
  std::ofstream sounding(files.sounding_path);
  sounding << "source,on_s,off_s\n";
  for (const engine::SoundingInterval& s : rendered->sounding) {
    const double delay_s = travel_s[static_cast<size_t>(s.source)];
    std::string row = std::to_string(s.source);
    AppendField(s.on_s + delay_s, &row);
    AppendField(s.off_s + delay_s, &row);
    sounding << row << '\n';
  }
  if (!sounding.flush()) return InvalidArgument(files.sounding_path + ": write failed");
  return files;
}

}  // namespace localizer::io
