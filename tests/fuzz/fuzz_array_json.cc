// array.json text -> ParseArrayJson (what ReadArrayJson runs on a file's contents). An
// accepted file holds what array_json.h documents, says what the JSON says (the reference
// sensor is the integer written, not a truncation of it), and reads back the same after
// WriteArrayJson (its "session" settings included).
#include <nlohmann/json.hpp>

#include "clients/io/array_json.h"
#include "engine/array/array_geometry.h"
#include "fuzz_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace localizer;
  const std::string text(reinterpret_cast<const char*>(data), size);
  auto array = io::ParseArrayJson(text, "array.json");
  if (!array.ok()) {
    FUZZ_CHECK(array.status().code() == StatusCode::kInvalidArgument, array.status().ToString());
    return 0;
  }
  const int sensors = static_cast<int>(array->sensors_m.size());
  FUZZ_CHECK(sensors >= 4, std::to_string(sensors));
  FUZZ_CHECK(array->reference_sensor >= 0 && array->reference_sensor < sensors,
             std::to_string(array->reference_sensor));
  FUZZ_CHECK(std::isfinite(array->sound_speed_mps) && array->sound_speed_mps > 0.0, "sound speed");
  if (array->sample_rate_hz) FUZZ_CHECK(std::isfinite(*array->sample_rate_hz) && *array->sample_rate_hz > 0.0, "rate");
  if (array->band_hz)
    FUZZ_CHECK(array->band_hz->first >= 0.0 && array->band_hz->second > array->band_hz->first, "band");
  for (int axis = 0; axis < 3; ++axis) {
    FUZZ_CHECK(array->bounds_min_m[axis] < array->bounds_max_m[axis], "bounds");
    FUZZ_CHECK(array->bounds_min_m[axis] != std::numeric_limits<double>::infinity(), "min at +inf");
    FUZZ_CHECK(array->bounds_max_m[axis] != -std::numeric_limits<double>::infinity(), "max at -inf");
  }
  FUZZ_CHECK(engine::ArrayGeometry::Create(array->sensors_m, array->sound_speed_mps, array->reference_sensor).ok(),
             "accepted a geometry the engine refuses");
  // The file parsed: it is JSON, and the integer it gives is the one kept.
  const nlohmann::json root = nlohmann::json::parse(text);
  if (root.contains("reference_sensor")) {
    const nlohmann::json& reference = root["reference_sensor"];
    const bool same = reference.is_number_unsigned()
                          ? reference.get<uint64_t>() == static_cast<uint64_t>(array->reference_sensor)
                          : reference.get<int64_t>() == array->reference_sensor;
    FUZZ_CHECK(same, "reference_sensor " + reference.dump() + " read as " + std::to_string(array->reference_sensor));
  }
  // Written and read back: the same array.
  static fuzz::MemFile file;
  const std::string& path = file.Write(nullptr, 0);
  FUZZ_CHECK(io::WriteArrayJson(path, *array).ok(), "write");
  auto again = io::ReadArrayJson(path);
  FUZZ_CHECK(again.ok(), "written array refused: " + again.status().ToString());
  FUZZ_CHECK(again->sensors_m == array->sensors_m && again->sound_speed_mps == array->sound_speed_mps &&
                 again->sample_rate_hz == array->sample_rate_hz && again->reference_sensor == array->reference_sensor &&
                 again->band_hz == array->band_hz && again->bounds_min_m == array->bounds_min_m &&
                 again->bounds_max_m == array->bounds_max_m && again->localization == array->localization &&
                 again->source_side_normal == array->source_side_normal && again->max_sources == array->max_sources,
             "array changes on a write and read");
  FUZZ_CHECK(io::SessionSettingsToJson(again->session) == io::SessionSettingsToJson(array->session),
             "session changes on a write and read: " + io::SessionSettingsToJson(array->session).dump());
  return 0;
}
