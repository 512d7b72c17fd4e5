// The radar scenario simulator: the seed's timing and range, truth, detection probability,
// clutter count and plot noise, replay by seed.
#include "engine/sim/radar_scan.h"

#include <gtest/gtest.h>

#include <cmath>

namespace localizer::engine {
namespace {

TEST(RadarScan, SeedTimingRangeAndTruth) {
  RadarScanOptions o;
  EXPECT_NEAR(o.period_s(), 1.8182, 1e-4);     // 33 rpm
  EXPECT_NEAR(o.OuterRangeM(), 83275.0, 1.0);  // c / (2 x 1800 Hz)
  auto sim = RadarScanSimulator::Create(o, SeedCaseTargets());
  ASSERT_TRUE(sim.ok());
  const RadarScanFrame f = sim->Frame(10);
  EXPECT_NEAR(f.scan.time_s, 18.182, 1e-3);
  ASSERT_EQ(f.truth.size(), 1u);
  EXPECT_NEAR(f.truth[0].position_m.x(), 1000.0 - 10.0 * 18.182, 0.01);
  EXPECT_NEAR(f.truth[0].position_m.y(), 1000.0, 1e-9);
  EXPECT_NEAR(f.truth[0].velocity_mps.x(), -10.0, 1e-12);
}

TEST(RadarScan, DetectionProbabilityClutterCountAndNoise) {
  RadarScanOptions o;
  o.max_range_m = 30000.0;
  o.detection_probability = 0.9;
  o.clutter_density_per_m2 = 1e-8;  // mean 28.3 false plots per scan
  o.range_sigma_m = 20.0;
  o.bearing_sigma_rad = 0.02;
  o.seed = 3;
  auto sim = RadarScanSimulator::Create(o, RingTargets(10, 15000.0, 100.0, {0.0, 0.0}));
  ASSERT_TRUE(sim.ok());
  const int scans = 400;
  double detected = 0, clutter = 0, sum_r2 = 0, sum_b2 = 0, covered = 0;
  for (int k = 0; k < scans; ++k) {
    const RadarScanFrame f = sim->Frame(k);
    covered += static_cast<double>(f.truth.size());  // targets leave the 30 km annulus
    for (size_t j = 0; j < f.source.size(); ++j) {
      if (j > 0) {
        EXPECT_LE(f.scan.detections[j - 1].bearing_rad, f.scan.detections[j].bearing_rad);
      }
      const Detection& d = f.scan.detections[j];
      EXPECT_GE(d.range_m, o.min_range_m - 100.0);
      EXPECT_LE(d.range_m, o.max_range_m + 100.0);
      if (f.source[j] < 0) {
        ++clutter;
        continue;
      }
      ++detected;
      const TargetTruth* found = nullptr;
      for (const TargetTruth& t : f.truth) {
        if (t.id == static_cast<uint64_t>(f.source[j])) found = &t;
      }
      ASSERT_NE(found, nullptr) << "a plot of a target outside the annulus";
      const TargetTruth& t = *found;
      const double dr = d.range_m - t.position_m.head<2>().norm();
      const double db = std::remainder(d.bearing_rad - std::atan2(t.position_m.y(), t.position_m.x()), 2 * M_PI);
      sum_r2 += dr * dr;
      sum_b2 += db * db;
    }
  }
  const double expected_clutter = o.clutter_density_per_m2 * o.AreaM2() * scans;
  EXPECT_NEAR(clutter, expected_clutter, 4.0 * std::sqrt(expected_clutter));
  ASSERT_GT(covered, 1000.0);
  EXPECT_NEAR(detected / covered, 0.9, 4.0 * std::sqrt(0.09 / covered));
  EXPECT_NEAR(std::sqrt(sum_r2 / detected), 20.0, 1.0);
  EXPECT_NEAR(std::sqrt(sum_b2 / detected), 0.02, 0.001);
}

TEST(RadarScan, ScansReplayAloneAndRejectBadOptions) {
  RadarScanOptions o;
  o.clutter_density_per_m2 = 1e-9;
  auto sim = RadarScanSimulator::Create(o, RandomTargets(20, 5000.0, 60000.0, 1000.0, 9));
  ASSERT_TRUE(sim.ok());
  const RadarScanFrame a = sim->Frame(7), b = sim->Frame(7);
  ASSERT_EQ(a.scan.detections.size(), b.scan.detections.size());
  for (size_t j = 0; j < a.scan.detections.size(); ++j) {
    EXPECT_EQ(a.scan.detections[j].range_m, b.scan.detections[j].range_m);
  }
  o.detection_probability = 1.5;
  EXPECT_EQ(RadarScanSimulator::Create(o, {}).status().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace localizer::engine
