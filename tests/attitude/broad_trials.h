// Shared by the tests on the BROAD trials (broad_test, mag_disturbance_test): where the
// three trials are, reading them once, and running a filter over one with its score.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "clients/io/imu_csv.h"
#include "engine/attitude/attitude_error.h"
#include "engine/attitude/attitude_filter.h"
#include "tests/attitude/estimate_dump.h"

namespace localizer::engine::testing {

inline std::vector<std::string> BroadTrialPaths() {
  const std::string dir = std::string(LOCALIZER_DATA_DIR) + "/broad-subset/";
  return {dir + "02_undisturbed_slow_rotation_B.csv", dir + "16_undisturbed_fast_translation_B.csv",
          dir + "25_disturbed_tapping_B.csv"};
}

// The trial at `path`, read once per test program (with magnetometer and truth); nullptr
// (and a test failure) when it cannot be read.
inline const io::ImuRecording* BroadTrial(const std::string& path) {
  static std::map<std::string, io::ImuRecording> trials;
  auto it = trials.find(path);
  if (it == trials.end()) {
    auto read = io::ReadImuCsv(path, /*need_mag=*/true, /*need_truth=*/true);
    EXPECT_TRUE(read.ok()) << read.status().ToString();
    if (!read.ok()) return nullptr;
    it = trials.emplace(path, std::move(*read)).first;
  }
  return &it->second;
}

// The time of the first scored sample (movement = 1 with finite truth).
inline double FirstMovement_s(const io::ImuRecording& trial) {
  for (size_t i = 0; i < trial.samples.size(); ++i) {
    if (trial.movement[i] && trial.truth[i].coeffs().allFinite()) return trial.samples[i].t_s;
  }
  return 0.0;
}

struct TrialResult {
  AttitudeScore score;
  double mean_signed_heading_rad = 0.0;  // mean of the signed heading error (scored samples)
};

// Runs a fresh filter with `options` over `samples` (the trial's, possibly disturbed) and
// scores it against the trial's truth the benchmark's way.
inline TrialResult RunTrial(const io::ImuRecording& trial, const std::vector<ImuSample>& samples,
                            const AttitudeFilterOptions& options) {
  auto filter = CreateAttitudeFilter(options);
  EXPECT_TRUE(filter.ok());
  if (!filter.ok()) return {};
  std::vector<Eigen::Quaterniond> estimates;
  estimates.reserve(samples.size());
  double heading_sum = 0.0;
  int heading_count = 0;
  for (size_t i = 0; i < samples.size(); ++i) {
    const Status status = (*filter)->Update(samples[i]);
    EXPECT_TRUE(status.ok()) << status.ToString();
    const AttitudeEstimate estimate = (*filter)->estimate();
    DumpEstimate(estimate);
    estimates.push_back(estimate.body_to_world);
    if (trial.movement[i] && trial.truth[i].coeffs().allFinite()) {
      Eigen::Quaterniond e = estimates.back() * trial.truth[i].conjugate();
      if (e.w() < 0.0) e.coeffs() = -e.coeffs();
      heading_sum += 2.0 * std::atan2(e.z(), e.w());
      ++heading_count;
    }
  }
  auto score = ScoreAttitude(estimates, trial.truth, trial.movement);
  EXPECT_TRUE(score.ok()) << score.status().ToString();
  return {score.ok() ? *score : AttitudeScore{}, heading_sum / std::max(heading_count, 1)};
}

inline TrialResult RunTrial(const io::ImuRecording& trial, const AttitudeFilterOptions& options) {
  return RunTrial(trial, trial.samples, options);
}

}  // namespace localizer::engine::testing
