// Magnetic disturbances of our own on the three real BROAD trials (issue 22): the real
// motion, gyro and accelerometer, and the real magnetometer with a synthetic disturbance
// added (engine/sim/magnetic_disturbance.h), scored against the real optical truth over the
// movement phase. One parameter set (the defaults) for every case. Cases, per trial:
//   clean         the recording as it is (the reference);
//   magnet_mid    a magnet appears on the sensor 20 s into the movement: 60 µT hard iron in a
//                 seeded random direction, soft iron within ±5 %;
//   magnet_start  a magnet rides on the sensor from the first sample (the initial rest and
//                 heading see it too): 150 µT (far outside any norm gate) and 25 µT (inside
//                 it part of the time), soft iron within ±3 %;
//   objects       the sensor passes three ferrous objects fixed in the world (20 s, 50 s and
//                 80 s into the movement): 40 µT at the closest pass, Gaussian envelope of 2 s.
// The directions are drawn from seeds fixed per trial and case, not chosen.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "engine/sim/magnetic_disturbance.h"
#include "tests/attitude/broad_trials.h"

namespace localizer::engine {
namespace {

constexpr double kDeg = M_PI / 180.0;

enum class Case { kClean, kMagnetMid, kMagnetStartLarge, kMagnetStartSmall, kObjects };
constexpr Case kCases[] = {Case::kClean, Case::kMagnetMid, Case::kMagnetStartLarge, Case::kMagnetStartSmall,
                           Case::kObjects};

const char* CaseName(Case c) {
  switch (c) {
    case Case::kClean: return "clean";
    case Case::kMagnetMid: return "magnet_mid";
    case Case::kMagnetStartLarge: return "magnet_start_150uT";
    case Case::kMagnetStartSmall: return "magnet_start_25uT";
    case Case::kObjects: return "objects";
  }
  return "?";
}

std::vector<ImuSample> Disturbed(const io::ImuRecording& trial, Case c, uint64_t seed) {
  std::vector<ImuSample> samples = trial.samples;
  const double move_s = testing::FirstMovement_s(trial);
  switch (c) {
    case Case::kClean:
      break;
    case Case::kMagnetMid:
      AddBodyFixedMagnet(RandomBodyFixedMagnet(60.0, 0.05, move_s + 20.0, seed), &samples);
      break;
    case Case::kMagnetStartLarge:
      AddBodyFixedMagnet(RandomBodyFixedMagnet(150.0, 0.03, -1e9, seed + 100), &samples);
      break;
    case Case::kMagnetStartSmall:
      AddBodyFixedMagnet(RandomBodyFixedMagnet(25.0, 0.03, -1e9, seed + 200), &samples);
      break;
    case Case::kObjects:
      for (int k = 0; k < 3; ++k) {
        AddPassingObject(RandomPassingObject(40.0, move_s + 20.0 + 30.0 * k, 2.0, seed + 300 + k), trial.truth,
                         &samples);
      }
      break;
  }
  return samples;
}

// Total RMSE with the magnetometer (9D) per case and trial, and the 6D inclination of the
// clean trials, with `options` (use_mag is set here).
struct Table {
  double total_deg[5][3] = {};
  double inclination_6d_deg[3] = {};
};

Table Evaluate(AttitudeFilterOptions options) {
  Table table;
  const std::vector<std::string> paths = testing::BroadTrialPaths();
  for (size_t t = 0; t < paths.size(); ++t) {
    const io::ImuRecording* trial = testing::BroadTrial(paths[t]);
    if (trial == nullptr) return table;
    options.use_mag = false;
    table.inclination_6d_deg[t] = testing::RunTrial(*trial, options).score.inclination_rmse_rad / kDeg;
    options.use_mag = true;
    for (const Case c : kCases) {
      const std::vector<ImuSample> samples = Disturbed(*trial, c, 1000 * (t + 1));
      table.total_deg[static_cast<int>(c)][t] =
          testing::RunTrial(*trial, samples, options).score.total_rmse_rad / kDeg;
    }
  }
  return table;
}

void Print(const char* title, const Table& table) {
  std::printf("%s\n%-20s %7s %7s %7s %7s\n", title, "case (9D total deg)", "02", "16", "25", "mean");
  for (const Case c : kCases) {
    const double* row = table.total_deg[static_cast<int>(c)];
    std::printf("%-20s %7.2f %7.2f %7.2f %7.2f\n", CaseName(c), row[0], row[1], row[2],
                (row[0] + row[1] + row[2]) / 3.0);
  }
  const double* i6 = table.inclination_6d_deg;
  std::printf("%-20s %7.2f %7.2f %7.2f %7.2f\n", "6D inclination", i6[0], i6[1], i6[2], (i6[0] + i6[1] + i6[2]) / 3.0);
}

TEST(MagDisturbanceTest, DefaultsSurviveTheDisturbances) {
  const Table table = Evaluate(AttitudeFilterOptions{});
  Print("quaternion MEKF, defaults", table);
  for (int t = 0; t < 3; ++t) {
    EXPECT_LT(table.total_deg[static_cast<int>(Case::kClean)][t], 2.0) << "trial " << t;
    EXPECT_LT(table.total_deg[static_cast<int>(Case::kMagnetMid)][t], 3.0) << "trial " << t;
    EXPECT_LT(table.total_deg[static_cast<int>(Case::kMagnetStartLarge)][t], 4.0) << "trial " << t;
    EXPECT_LT(table.total_deg[static_cast<int>(Case::kMagnetStartSmall)][t], 4.0) << "trial " << t;
    EXPECT_LT(table.total_deg[static_cast<int>(Case::kObjects)][t], 3.0) << "trial " << t;
  }
}

}  // namespace
}  // namespace localizer::engine
