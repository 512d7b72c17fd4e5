#include "clients/io/xav_array.h"

#include <algorithm>
#include <filesystem>

#include "clients/io/csv_table.h"
#include "clients/io/xav_config.h"

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
  auto channel_column = table->Column("array_channel");
  XavArray xav;
  std::vector<int> channels;
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
    int channel = static_cast<int>(r);
    if (channel_column.ok()) {
      auto value = table->Number(r, *channel_column);
      if (!value.ok()) return value.status();
      channel = static_cast<int>(*value);
    }
    channels.push_back(channel);
  }

  // The deployment's own files beside the CSV say the rest.
  const std::string dir = std::filesystem::path(path).parent_path().string();
  auto yaml = FindOneFile(dir, "localization_config", ".yaml");
  if (!yaml.ok()) {
    return Status(yaml.status().code(), path + ": the sound speed and reference channel come from the deployment's " +
                                            "localization config beside it: " + yaml.status().message());
  }
  auto localization = ReadXavLocalizationYaml(*yaml);
  if (!localization.ok()) return localization.status();
  const std::string sheet = (std::filesystem::path(dir) / "deployment_info.csv").string();
  auto deployment = ReadXavDeploymentCsv(sheet);
  if (!deployment.ok()) {
    return Status(deployment.status().code(), path + ": the sample rate and water column come from " + sheet + ": " +
                                                  deployment.status().message());
  }
  const size_t n = xav.array.sensors_m.size();
  if (static_cast<size_t>(localization->reference_sensor) >= n) {
    return InvalidArgument(*yaml + ": TDOA.ref_channel " + std::to_string(localization->reference_sensor) + " but " +
                           path + " has " + std::to_string(n) + " hydrophones");
  }
  if (deployment->hydrophone_depth_m.size() != n) {
    return InvalidArgument(sheet + ": " + std::to_string(deployment->hydrophone_depth_m.size()) + " channels but " +
                           path + " has " + std::to_string(n) + " hydrophones");
  }
  std::vector<double> surfaces_m;
  for (size_t k = 0; k < n; ++k) {
    if (channels[k] < 0 || static_cast<size_t>(channels[k]) >= n) {
      return InvalidArgument(path + ": array_channel " + std::to_string(channels[k]) + " out of range");
    }
    surfaces_m.push_back(deployment->hydrophone_depth_m[static_cast<size_t>(channels[k])] + xav.array.sensors_m[k].z());
  }
  std::sort(surfaces_m.begin(), surfaces_m.end());
  xav.surface_z_m = n % 2 == 1 ? surfaces_m[n / 2] : 0.5 * (surfaces_m[n / 2 - 1] + surfaces_m[n / 2]);
  xav.water_depth_m = deployment->water_depth_m;
  xav.array.sound_speed_mps = localization->sound_speed_mps;
  xav.array.reference_sensor = localization->reference_sensor;
  xav.array.sample_rate_hz = deployment->sample_rate_hz;
  xav.array.bounds_max_m.z() = xav.surface_z_m;
  xav.array.bounds_min_m.z() = xav.surface_z_m - xav.water_depth_m;
  // Where the mooring was; the sheet does not say which way the frame's axes point.
  GeodeticOrigin origin;
  origin.latitude_deg = deployment->latitude_deg;
  origin.longitude_deg = deployment->longitude_deg;
  origin.altitude_m = -xav.surface_z_m;  // the frame's origin, surface_z_m below sea level
  xav.array.geodetic_origin = origin;
  return xav;
}

StatusOr<std::vector<std::string>> FindXavRecordings(const std::string& dir, const std::vector<std::string>& roots) {
  std::vector<std::string> paths;
  for (const std::string& root : roots) {
    if (root.empty()) return NotFound(dir + ": a hydrophone has no file_name_root to find its recording by");
    auto path = FindOneFile(dir, root, ".wav");
    if (!path.ok()) {
      if (path.status().code() == StatusCode::kNotFound) return path.status();
      return InvalidArgument(path.status().message() + "; keep one recording per hydrophone");
    }
    paths.push_back(*path);
  }
  return paths;
}

}  // namespace localizer::io
