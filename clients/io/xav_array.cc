#include "clients/io/xav_array.h"

#include <algorithm>
#include <filesystem>

#include "clients/io/csv_table.h"

namespace localizer::io {

StatusOr<XavArray> ReadXavHydrophoneCsv(const std::string& path) {
  auto table = CsvTable::Read(path);
  if (!table.ok()) return table.status();
  int columns[3];
  const char* names[3] = {"x", "y", "z"};
  for (int axis = 0; axis < 3; ++axis) {
    auto column = table->Column(names[axis]);
    if (!column.ok()) return column.status();
    columns[axis] = *column;
  }
  auto root_column = table->Column("file_name_root");
  XavArray xav;
  xav.array.sound_speed_mps = kXavSoundSpeedMps;
  xav.array.reference_sensor = kXavReferenceSensor;
  xav.array.sample_rate_hz = kXavSampleRateHz;
  xav.array.bounds_max_m.z() = kXavSurfaceZM;
  xav.array.bounds_min_m.z() = kXavBottomZM;
  for (size_t r = 0; r < table->row_count(); ++r) {
    engine::Vec3 position_m;
    for (int axis = 0; axis < 3; ++axis) {
      auto value = table->Number(r, columns[axis]);
      if (!value.ok()) return value.status();
      position_m[axis] = *value;
    }
    xav.array.sensors_m.push_back(position_m);
    // The file root is only needed to find recordings; its absence is not an error.
    xav.file_name_roots.push_back(root_column.ok() ? table->Text(r, *root_column) : "");
  }
  if (xav.array.sensors_m.size() <= kXavReferenceSensor) {
    return InvalidArgument(path + ": " + std::to_string(xav.array.sensors_m.size()) +
                           " hydrophones; the XAV array has 6 (reference is hydrophone 3)");
  }
  return xav;
}

StatusOr<std::vector<std::string>> FindXavRecordings(const std::string& dir, const std::vector<std::string>& roots) {
  std::error_code error;
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir, error)) {
    names.push_back(entry.path().filename().string());
  }
  if (error) return NotFound(dir + ": " + error.message());
  std::sort(names.begin(), names.end());
  std::vector<std::string> paths;
  for (const std::string& root : roots) {
    std::vector<std::string> matches;
    for (const std::string& name : names) {
      if (!root.empty() && name.starts_with(root) && name.ends_with(".wav")) {
        matches.push_back(name);
      }
    }
    if (matches.empty()) return NotFound(dir + ": no " + root + "*.wav");
    if (matches.size() > 1) {
      return InvalidArgument(dir + ": several " + root + "*.wav (" + matches[0] + ", " + matches[1] +
                             "); keep one recording per hydrophone");
    }
    paths.push_back((std::filesystem::path(dir) / matches.front()).string());
  }
  return paths;
}

}  // namespace localizer::io
