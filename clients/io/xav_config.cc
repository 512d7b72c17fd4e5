#include "clients/io/xav_config.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include <yaml-cpp/yaml.h>

#include "clients/io/csv_table.h"

namespace localizer::io {

StatusOr<XavLocalizationConfig> ReadXavLocalizationYaml(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    return NotFound(path + ": cannot read");
  } catch (const YAML::Exception& e) {
    return InvalidArgument(path + ": not YAML: " + e.what());
  }
  XavLocalizationConfig config;
  try {
    const YAML::Node speed = root["ENVIRONMENT"]["sound_speed_mps"];
    if (!speed) return InvalidArgument(path + ": ENVIRONMENT.sound_speed_mps missing");
    config.sound_speed_mps = speed.as<double>();
    const YAML::Node ref = root["TDOA"]["ref_channel"];
    if (!ref) return InvalidArgument(path + ": TDOA.ref_channel missing");
    config.reference_sensor = ref.as<int>();
  } catch (const YAML::Exception& e) {
    return InvalidArgument(path + ": ENVIRONMENT.sound_speed_mps must be a number and TDOA.ref_channel an integer (" +
                           e.what() + ")");
  }
  if (!(config.sound_speed_mps > 0.0 && config.sound_speed_mps < 1e4)) {
    return InvalidArgument(path + ": ENVIRONMENT.sound_speed_mps must be in (0, 10000) m/s");
  }
  if (config.reference_sensor < 0) return InvalidArgument(path + ": TDOA.ref_channel must be >= 0");
  return config;
}

StatusOr<XavDeployment> ReadXavDeploymentCsv(const std::string& path) {
  auto table = CsvTable::Read(path);
  if (!table.ok()) return table.status();
  const char* names[] = {"audio_channel_number", "sampling_frequency", "hydrophone_depth", "location_water_depth",
                         "location_lat", "location_lon"};
  int column[6];
  for (int i = 0; i < 6; ++i) {
    auto c = table->Column(names[i]);
    if (!c.ok()) return c.status();
    column[i] = *c;
  }
  const size_t rows = table->row_count();
  if (rows == 0 || rows > 1024) return InvalidArgument(path + ": needs 1 to 1024 channel rows");
  XavDeployment d;
  d.hydrophone_depth_m.assign(rows, NAN);
  for (size_t r = 0; r < rows; ++r) {
    double v[6];
    for (int i = 0; i < 6; ++i) {
      auto n = table->Number(r, column[i]);
      if (!n.ok()) return n.status();
      v[i] = *n;
    }
    const double channel = v[0];
    if (!(channel >= 0.0 && channel < static_cast<double>(rows)) || channel != std::floor(channel) ||
        !std::isnan(d.hydrophone_depth_m[static_cast<size_t>(channel)])) {
      return InvalidArgument(path + ": audio_channel_number must run over 0.." + std::to_string(rows - 1) +
                             ", each once (row " + std::to_string(r + 2) + ")");
    }
    if (!(v[1] > 0.0) || !(v[3] > 0.0) || !std::isfinite(v[2])) {
      return InvalidArgument(path + ": row " + std::to_string(r + 2) +
                             ": sampling_frequency and location_water_depth must be positive, hydrophone_depth finite");
    }
    if (r == 0) {
      d.sample_rate_hz = v[1];
      d.water_depth_m = v[3];
      d.latitude_deg = v[4];
      d.longitude_deg = v[5];
    } else if (v[1] != d.sample_rate_hz || v[3] != d.water_depth_m) {
      return InvalidArgument(path + ": row " + std::to_string(r + 2) +
                             ": sampling_frequency and location_water_depth differ from the first row's");
    }
    d.hydrophone_depth_m[static_cast<size_t>(channel)] = v[2];
  }
  return d;
}

StatusOr<std::string> FindOneFile(const std::string& dir, const std::string& prefix, const std::string& suffix) {
  std::error_code error;
  std::vector<std::string> matches;
  for (const auto& entry : std::filesystem::directory_iterator(dir.empty() ? "." : dir, error)) {
    const std::string name = entry.path().filename().string();
    if (name.starts_with(prefix) && name.ends_with(suffix)) matches.push_back(entry.path().string());
  }
  if (error) return NotFound(dir + ": " + error.message());
  if (matches.empty()) return NotFound((dir.empty() ? "." : dir) + ": no " + prefix + "*" + suffix);
  if (matches.size() > 1) {
    std::sort(matches.begin(), matches.end());
    return InvalidArgument(dir + ": several " + prefix + "*" + suffix + " (" + matches[0] + ", " + matches[1] + ")");
  }
  return matches.front();
}

}  // namespace localizer::io
