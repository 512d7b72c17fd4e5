// Shared by the attitude tests: run a filter over synthetic samples and measure its error
// against the trajectory that made them.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "engine/attitude/attitude_error.h"
#include "engine/attitude/attitude_filter.h"
#include "engine/sim/platform_motion.h"
#include "tests/attitude/estimate_dump.h"

namespace localizer::engine::testing {

// Largest errors over the samples with t_s >= from_s (the filter sees every sample).
struct RunErrors {
  double max_total_rad = 0.0;
  double max_heading_rad = 0.0;
  double max_inclination_rad = 0.0;
  AttitudeEstimate last;
};

inline RunErrors RunFilter(const AttitudeFilterOptions& options, const AttitudeTrajectory& truth,
                           const std::vector<ImuSample>& samples, double from_s = 0.0) {
  RunErrors errors;
  auto filter = CreateAttitudeFilter(options);
  EXPECT_TRUE(filter.ok()) << filter.status().ToString();
  if (!filter.ok()) return errors;
  for (const ImuSample& s : samples) {
    const Status status = (*filter)->Update(s);
    EXPECT_TRUE(status.ok()) << status.ToString();
    const AttitudeEstimate estimate = (*filter)->estimate();
    DumpEstimate(estimate);
    if (s.t_s < from_s) continue;
    const AttitudeError e = AttitudeErrorOf(estimate.body_to_world, truth.At(s.t_s));
    errors.max_total_rad = std::max(errors.max_total_rad, e.total_rad);
    errors.max_heading_rad = std::max(errors.max_heading_rad, e.heading_rad);
    errors.max_inclination_rad = std::max(errors.max_inclination_rad, e.inclination_rad);
  }
  errors.last = (*filter)->estimate();
  return errors;
}

constexpr double kDeg = M_PI / 180.0;

// A consumer-grade IMU: 0.005 rad/s gyro, 0.05 m/s^2 accelerometer, 0.5 µT magnetometer
// noise per sample, no bias.
inline ImuNoise ConsumerImuNoise() {
  ImuNoise noise;
  noise.gyro_noise_sd_rps = 0.005;
  noise.accel_noise_sd_mps2 = 0.05;
  noise.mag_noise_sd_uT = 0.5;
  return noise;
}

// Roll, pitch and yaw swinging; pitch with amplitude 1.8 rad, so it passes +-90 degrees
// (first at about 2.5 s).
inline AttitudeTrajectory ThroughNinetyDegreesPitch() {
  AttitudeTrajectoryOptions motion;
  motion.amplitude_rad = {0.3, 1.8, 0.5};
  motion.frequency_hz = {0.2, 0.1, 0.07};
  return AttitudeTrajectory(motion);
}

}  // namespace localizer::engine::testing
