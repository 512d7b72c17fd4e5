// Test-side reader of the shared BROAD trials (../shared/data/broad-subset, see its README):
// the tests link only the engine, so this small reader stands in for clients/io/imu_csv.
// Columns are found by header name; any malformed line fails the read.
#pragma once

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "engine/core/imu.h"

namespace localizer::engine::testing {

struct BroadTrial {
  std::vector<ImuSample> samples;
  std::vector<Eigen::Quaterniond> truth;  // NaN where the markers dropped out
  std::vector<bool> movement;
};

// False (and `error` says why) when the file cannot be read or lacks a column.
inline bool ReadBroadTrial(const std::string& path, BroadTrial* trial, std::string* error) {
  std::ifstream in(path);
  if (!in) {
    *error = "cannot open " + path;
    return false;
  }
  std::string line;
  std::getline(in, line);
  std::vector<std::string> header;
  {
    std::stringstream ss(line);
    std::string field;
    while (std::getline(ss, field, ',')) header.push_back(field);
  }
  const char* names[] = {"t_s",        "gyr_x_rps",  "gyr_y_rps",  "gyr_z_rps",  "acc_x_mps2",
                         "acc_y_mps2", "acc_z_mps2", "mag_x_uT",   "mag_y_uT",   "mag_z_uT",
                         "truth_qw",   "truth_qx",   "truth_qy",   "truth_qz",   "movement"};
  int column[15];
  for (int i = 0; i < 15; ++i) {
    column[i] = -1;
    for (size_t c = 0; c < header.size(); ++c) {
      if (header[c] == names[i]) column[i] = static_cast<int>(c);
    }
    if (column[i] < 0) {
      *error = path + " has no column " + names[i];
      return false;
    }
  }
  std::vector<double> fields;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    fields.clear();
    std::stringstream ss(line);
    std::string field;
    while (std::getline(ss, field, ',')) fields.push_back(std::strtod(field.c_str(), nullptr));
    if (fields.size() != header.size()) {
      *error = path + ": a line has " + std::to_string(fields.size()) + " fields";
      return false;
    }
    auto at = [&](int i) { return fields[column[i]]; };
    ImuSample s;
    s.t_s = at(0);
    s.gyro_rps = {at(1), at(2), at(3)};
    s.accel_mps2 = {at(4), at(5), at(6)};
    s.mag_uT = {at(7), at(8), at(9)};
    trial->samples.push_back(s);
    trial->truth.emplace_back(at(10), at(11), at(12), at(13));  // (w, x, y, z)
    trial->movement.push_back(at(14) == 1.0);
  }
  return true;
}

inline std::vector<std::string> BroadTrialPaths() {
  const std::string dir = std::string(LOCALIZER_DATA_DIR) + "/broad-subset/";
  return {dir + "02_undisturbed_slow_rotation_B.csv", dir + "16_undisturbed_fast_translation_B.csv",
          dir + "25_disturbed_tapping_B.csv"};
}

}  // namespace localizer::engine::testing
