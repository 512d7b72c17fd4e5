// Magnetic disturbances of our own on the three real BROAD trials (issue 22): the real
// motion, gyro and accelerometer, and the real magnetometer with a synthetic disturbance
// added (engine/sim/magnetic_disturbance.h), scored against the real optical truth over the
// movement phase. One parameter set (the defaults) for every case. Cases, per trial:
//   clean         the recording as it is (the reference);
//   magnet_mid    a magnet appears on the sensor 20 s into the movement: 60 µT hard iron in a
//                 seeded random direction, soft iron within ±2 % (a magnet's own permeability
//                 is near 1; iron parts would add more, which a hard-iron fit cannot remove);
//                 magnet_mid_25uT: the same with 25 µT (inside the norm gate part of the time);
//   magnet_start  a magnet rides on the sensor from the first sample (the initial rest and
//                 heading see it too): 150 µT (far outside any norm gate) and 25 µT (inside
//                 it part of the time), soft iron within ±2 %. Before the sensor has turned
//                 enough to separate the offset from the Earth's field, nothing can tell the
//                 heading: these cases are also scored from 30 s into the movement;
//   objects       the sensor passes three ferrous objects fixed in the world (20 s, 50 s and
//                 80 s into the movement): 40 µT at the closest pass, Gaussian envelope of 2 s.
// The directions are drawn from seeds fixed per trial and case, not chosen. At the end, two
// simulated sensors (no recording needed) for the rule that believes a field disagreeing
// steadily with the gyro: not while the sensor barely turns, and again once it has turned.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "engine/attitude/quaternion_ekf.h"
#include "engine/sim/magnetic_disturbance.h"
#include "tests/attitude/attitude_test_util.h"
#include "tests/attitude/broad_trials.h"
#include "tests/attitude/iron_fixtures.h"
#include "tests/attitude/options_from_environment.h"

namespace localizer::engine {
namespace {

constexpr double kDeg = M_PI / 180.0;

enum class Case { kClean, kMagnetMid, kMagnetStartLarge, kMagnetStartSmall, kObjects, kMagnetMidSmall, kSoftIron };
constexpr Case kCases[] = {
    Case::kClean,   Case::kMagnetMid, Case::kMagnetMidSmall, Case::kMagnetStartLarge, Case::kMagnetStartSmall,
    Case::kObjects, Case::kSoftIron};
constexpr int kCaseCount = sizeof(kCases) / sizeof(kCases[0]);

const char* CaseName(Case c) {
  switch (c) {
    case Case::kClean:
      return "clean";
    case Case::kMagnetMid:
      return "magnet_mid";
    case Case::kMagnetMidSmall:
      return "magnet_mid_25uT";
    case Case::kMagnetStartLarge:
      return "magnet_start_150uT";
    case Case::kMagnetStartSmall:
      return "magnet_start_25uT";
    case Case::kObjects:
      return "objects";
    case Case::kSoftIron:
      return "soft_iron_5pct";
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
      AddBodyFixedMagnet(RandomBodyFixedMagnet(60.0, 0.02, move_s + 20.0, seed), &samples);
      break;
    case Case::kMagnetMidSmall:
      AddBodyFixedMagnet(RandomBodyFixedMagnet(25.0, 0.02, move_s + 20.0, seed + 400), &samples);
      break;
    case Case::kMagnetStartLarge:
      AddBodyFixedMagnet(RandomBodyFixedMagnet(150.0, 0.02, -1e9, seed + 100), &samples);
      break;
    case Case::kMagnetStartSmall:
      AddBodyFixedMagnet(RandomBodyFixedMagnet(25.0, 0.02, -1e9, seed + 200), &samples);
      break;
    case Case::kSoftIron:
      AddBodyFixedMagnet(RandomSoftIronMagnet(40.0, 0.05, -1e9, seed + 500), &samples);
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

// Total RMSE with the magnetometer (9D) per case and trial, the magnet_start cases also
// from 30 s into the movement, and the 6D inclination of the clean trials, with `options`
// (use_mag is set here).
struct Table {
  double total_deg[kCaseCount][3] = {};
  double late_total_deg[kCaseCount][3] = {};  // scored from 30 s into the movement
  double inclination_6d_deg[3] = {};
};

// seed_offset moves every case's draw (the study's check that the defaults were not fitted
// to one set of directions).
Table Evaluate(AttitudeFilterOptions options, uint64_t seed_offset = 0) {
  Table table;
  const std::vector<std::string> paths = testing::BroadTrialPaths();
  for (size_t t = 0; t < paths.size(); ++t) {
    const io::ImuRecording* trial = testing::BroadTrial(paths[t]);
    if (trial == nullptr) return table;
    options.use_mag = false;
    table.inclination_6d_deg[t] = testing::RunTrial(*trial, options).score.inclination_rmse_rad / kDeg;
    options.use_mag = true;
    io::ImuRecording late = *trial;
    const double late_s = testing::FirstMovement_s(*trial) + 30.0;
    for (size_t i = 0; i < late.samples.size(); ++i)
      late.movement[i] = late.movement[i] && late.samples[i].t_s >= late_s;
    for (const Case c : kCases) {
      const std::vector<ImuSample> samples = Disturbed(*trial, c, 1000 * (t + 1) + seed_offset);
      table.total_deg[static_cast<int>(c)][t] = testing::RunTrial(*trial, samples, options).score.total_rmse_rad / kDeg;
      table.late_total_deg[static_cast<int>(c)][t] =
          testing::RunTrial(late, samples, options).score.total_rmse_rad / kDeg;
    }
  }
  return table;
}

void PrintRow(const std::string& name, const double* row) {
  std::printf("%-30s %7.2f %7.2f %7.2f %7.2f\n", name.c_str(), row[0], row[1], row[2],
              (row[0] + row[1] + row[2]) / 3.0);
}

void Print(const char* title, const Table& table) {
  std::printf("%s\n%-30s %7s %7s %7s %7s\n", title, "case (9D total RMSE, deg)", "02", "16", "25", "mean");
  for (const Case c : kCases) {
    PrintRow(CaseName(c), table.total_deg[static_cast<int>(c)]);
    if (c == Case::kMagnetStartLarge || c == Case::kMagnetStartSmall || c == Case::kSoftIron) {
      PrintRow(std::string(CaseName(c)) + " from +30 s", table.late_total_deg[static_cast<int>(c)]);
    }
  }
  PrintRow("6D inclination (clean)", table.inclination_6d_deg);
}

// Bounds: about 1.5x what the defaults reach (and below what the filter without hard-iron
// estimation and the heading-consistency gate reached: magnet_mid_25uT 89 and 79 deg on
// trials 02 and 25, magnet_start from +30 s ~100 deg on trial 02, objects 2.3-4.1 deg). magnet_start is asserted on
// trial 02 only: trials 16 (translation) and 25 (tapping) turn too little for any fit to separate an offset present
// from the start from the Earth's field (rotation diversity 0.03 and 0.02 against 0.1
// needed), so the heading they start from stays wrong — printed, not asserted. Trial 25's
// magnet_mid cases coast on the gyro for their last 95 s (too little rotation to calibrate) and
// drifts by the gyro's bias in motion (about 0.05 deg/s there).
TEST(MagDisturbanceTest, DefaultsSurviveTheDisturbances) {
  const Table table = Evaluate(AttitudeFilterOptions{});
  Print("quaternion MEKF, defaults", table);
  for (int t = 0; t < 3; ++t) {
    EXPECT_LT(table.total_deg[static_cast<int>(Case::kClean)][t], 2.0) << "trial " << t;
    EXPECT_LT(table.total_deg[static_cast<int>(Case::kMagnetMid)][t], t == 2 ? 6.0 : 3.0) << "trial " << t;
    EXPECT_LT(table.total_deg[static_cast<int>(Case::kMagnetMidSmall)][t], t == 2 ? 7.0 : 3.0) << "trial " << t;
    EXPECT_LT(table.total_deg[static_cast<int>(Case::kObjects)][t], 2.7) << "trial " << t;
  }
  EXPECT_LT(table.late_total_deg[static_cast<int>(Case::kMagnetStartLarge)][0], 2.5);
  EXPECT_LT(table.late_total_deg[static_cast<int>(Case::kMagnetStartSmall)][0], 2.7);
}

// The estimates of a fresh filter with `options` over `samples`.
std::vector<Eigen::Quaterniond> Estimates(const std::vector<ImuSample>& samples, const AttitudeFilterOptions& options) {
  std::vector<Eigen::Quaterniond> estimates;
  auto filter = CreateAttitudeFilter(options);
  EXPECT_TRUE(filter.ok());
  if (!filter.ok()) return estimates;
  estimates.reserve(samples.size());
  for (const ImuSample& s : samples) {
    EXPECT_TRUE((*filter)->Update(s).ok());
    estimates.push_back((*filter)->estimate().body_to_world);
  }
  return estimates;
}

// What a disturbance costs: the RMS total angle between the estimates on the disturbed
// recording and on the clean one (same options), over the scored samples from `from_s` on.
// Unlike the error against the truth it does not contain the truth's own heading offset (about
// -1.3 deg on trials 02 and 25), which a distortion can happen to cancel or add to.
double AddedErrorDeg(const io::ImuRecording& trial, const std::vector<Eigen::Quaterniond>& disturbed,
                     const std::vector<Eigen::Quaterniond>& clean, double from_s) {
  double sum = 0.0;
  long count = 0;
  for (size_t i = 0; i < trial.samples.size() && i < disturbed.size() && i < clean.size(); ++i) {
    if (!trial.movement[i] || !trial.truth[i].coeffs().allFinite() || trial.samples[i].t_s < from_s) continue;
    const double e = AttitudeErrorOf(disturbed[i], clean[i]).total_rad;
    sum += e * e;
    ++count;
  }
  return std::sqrt(sum / static_cast<double>(std::max(count, 1L))) / kDeg;
}

// ±5 % soft iron with a 40 µT magnet on the sensor from the first sample (soft_iron_5pct),
// three draws per trial: the error it adds from 30 s into the movement (against the clean
// run), with the soft-iron fit (defaults) and with hard iron only (mag_soft_iron_max = 0).
TEST(MagDisturbanceTest, SoftIronFit) {
  AttitudeFilterOptions options;
  options.use_mag = true;
  AttitudeFilterOptions hard_only = options;
  hard_only.mag_soft_iron_max = 0.0;
  const std::vector<std::string> paths = testing::BroadTrialPaths();
  double with_fit_deg[3] = {}, hard_only_deg[3] = {};
  const uint64_t kDraws[] = {0, 7, 13};
  for (size_t t = 0; t < paths.size(); ++t) {
    const io::ImuRecording* trial = testing::BroadTrial(paths[t]);
    ASSERT_NE(trial, nullptr);
    const double from_s = testing::FirstMovement_s(*trial) + 30.0;
    const std::vector<Eigen::Quaterniond> clean = Estimates(trial->samples, options);
    for (const uint64_t draw : kDraws) {
      const std::vector<ImuSample> samples = Disturbed(*trial, Case::kSoftIron, 1000 * (t + 1) + draw);
      const double fit = AddedErrorDeg(*trial, Estimates(samples, options), clean, from_s);
      const double hard = AddedErrorDeg(*trial, Estimates(samples, hard_only), clean, from_s);
      std::printf("trial %zu draw %2lu: added error from +30 s %.2f deg with the soft-iron fit, %.2f hard iron only\n",
                  t, static_cast<unsigned long>(draw), fit, hard);
      with_fit_deg[t] += fit / 3.0;
      hard_only_deg[t] += hard / 3.0;
    }
  }
  std::printf("mean of the draws: with the fit %.2f %.2f %.2f deg, hard iron only %.2f %.2f %.2f deg\n",
              with_fit_deg[0], with_fit_deg[1], with_fit_deg[2], hard_only_deg[0], hard_only_deg[1], hard_only_deg[2]);
  // Trial 02 (slow rotation): measured 1.35 with the fit, 1.43 hard iron only. The fit is
  // trusted only from ~108 s (of 186) there, so most of the window is hard iron either way;
  // this bound is not one hard iron alone fails (soft_iron_estimator_test has that one).
  EXPECT_LT(with_fit_deg[0], 1.6);
  // Trials 16 and 25 barely rotate: the soft-iron fit is never trusted and changes nothing
  // (their large figures are the magnet present from the start, which no fit can separate).
  for (int t = 1; t < 3; ++t) EXPECT_LE(with_fit_deg[t], hard_only_deg[t] + 0.05) << "trial " << t;
}

// Not a test: the table with the options in ATT_OPT="name=value,..." (the sensitivity
// study in ACCURACY.md), the draws moved by ATT_SEED (default 0). Run with
// --gtest_also_run_disabled_tests.
TEST(MagDisturbanceTest, DISABLED_Study) {
  const char* text = std::getenv("ATT_OPT");
  const char* seed = std::getenv("ATT_SEED");
  Print(text != nullptr ? text : "defaults",
        Evaluate(testing::OptionsFromEnvironment(), seed != nullptr ? std::strtoull(seed, nullptr, 10) : 0));
}

// Not a test: a trace of one trial and case (ATT_TRIAL = 0..2, ATT_CASE = 0..6 in kCases order) every 2 s,
// draws moved by ATT_SEED as in the study, for looking at what the calibration does. Run with
// --gtest_also_run_disabled_tests.
TEST(MagDisturbanceTest, DISABLED_Trace) {
  const int t = std::getenv("ATT_TRIAL") ? std::atoi(std::getenv("ATT_TRIAL")) : 0;
  const int c = std::getenv("ATT_CASE") ? std::atoi(std::getenv("ATT_CASE")) : 0;
  const io::ImuRecording* trial = testing::BroadTrial(testing::BroadTrialPaths()[t]);
  ASSERT_NE(trial, nullptr);
  const uint64_t seed_offset = std::getenv("ATT_SEED") ? std::strtoull(std::getenv("ATT_SEED"), nullptr, 10) : 0;
  const std::vector<ImuSample> samples = Disturbed(*trial, kCases[c], 1000 * (t + 1) + seed_offset);
  AttitudeFilterOptions options = testing::OptionsFromEnvironment();
  options.use_mag = std::getenv("ATT_NOMAG") == nullptr;
  auto filter = std::make_unique<QuaternionEkf>(options);
  double next_s = 0.0;
  for (size_t i = 0; i < samples.size(); ++i) {
    ASSERT_TRUE(filter->Update(samples[i]).ok());
    if (samples[i].t_s < next_s) continue;
    next_s += 2.0;
    const AttitudeEstimate e = filter->estimate();
    const HardIronFit& fit = filter->hard_iron_fit();
    const SoftIronFit& soft = filter->soft_iron_fit();
    double total = NAN;
    if (trial->truth[i].coeffs().allFinite()) {
      Eigen::Quaterniond d = e.body_to_world * trial->truth[i].conjugate();
      if (d.w() < 0.0) d.coeffs() = -d.coeffs();
      total = std::copysign(AttitudeErrorOf(e.body_to_world, trial->truth[i]).total_rad / kDeg, d.z());
    }
    std::printf(
        "t %6.1f err %6.2f used %d cal %d div %.3f hdiv %.3f res %5.2f off %6.1f %6.1f %6.1f |m| %5.1f bz %.5f "
        "soft div %.3f res %5.2f dist %.3f ok %d A-I %.3f\n",
        samples[i].t_s, total, e.mag_used, e.mag_calibrated, fit.diversity, fit.heading_diversity, fit.residual_uT,
        e.mag_offset_uT.x(), e.mag_offset_uT.y(), e.mag_offset_uT.z(), samples[i].mag_uT.norm(),
        (e.body_to_world * e.gyro_bias_rps).z(), soft.diversity, soft.residual_uT, soft.distortion, soft.trusted,
        (e.mag_correction - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff());
  }
}

}  // namespace
}  // namespace localizer::engine

namespace localizer::engine {
namespace {

// Not a test: 6D inclination RMSE per trial binned by the gyro's rate (where the error is).
TEST(MagDisturbanceTest, DISABLED_InclinationByRate) {
  const AttitudeFilterOptions options = testing::OptionsFromEnvironment();
  for (const std::string& path : testing::BroadTrialPaths()) {
    const io::ImuRecording* trial = testing::BroadTrial(path);
    ASSERT_NE(trial, nullptr);
    auto filter = CreateAttitudeFilter(options);
    ASSERT_TRUE(filter.ok());
    const double edges[] = {0.5, 1.0, 2.0, 4.0, 1e9};
    double sum[5] = {}, count[5] = {};
    for (size_t i = 0; i < trial->samples.size(); ++i) {
      ASSERT_TRUE((*filter)->Update(trial->samples[i]).ok());
      if (!trial->movement[i] || !trial->truth[i].coeffs().allFinite()) continue;
      const double e = AttitudeErrorOf((*filter)->estimate().body_to_world, trial->truth[i]).inclination_rad / kDeg;
      int b = 0;
      while (trial->samples[i].gyro_rps.norm() > edges[b]) ++b;
      sum[b] += e * e;
      count[b] += 1;
    }
    std::printf("%s", path.substr(path.rfind('/') + 1, 2).c_str());
    for (int b = 0; b < 5; ++b)
      std::printf("  <%.1f: %.2f (%.0f%%)", edges[b], std::sqrt(sum[b] / std::max(count[b], 1.0)),
                  100.0 * count[b] / (count[0] + count[1] + count[2] + count[3] + count[4]));
    std::printf("\n");
  }
}

}  // namespace
}  // namespace localizer::engine

namespace localizer::engine {
namespace {

// Simulated sensors for the steady-disagreement rule (mag_consistency_s,
// mag_consistency_rate_rps): the Earth's field of the iron fixtures, a consumer IMU at
// kRateHz with a constant gyro bias the filter learns from the clean field, and a field
// change that stays inside the norm and dip gates: 6 µT horizontal and across the field's
// horizontal part (+0.7 % norm, -2 deg dip), which turns its azimuth by atan(6 / 17) = 19 deg.
constexpr double kAcross_uT = 6.0;

Eigen::Vector3d AcrossTheField() {  // world frame, unit: Up x the field's horizontal part
  const Eigen::Vector3d& m = testing::kEarthField_uT;
  return Eigen::Vector3d::UnitZ().cross(Eigen::Vector3d(m.x(), m.y(), 0.0)).normalized();
}

ImuNoise BiasedConsumerImu() {
  ImuNoise noise = testing::ConsumerImuNoise();
  noise.gyro_bias_rps = {0.002, -0.003, 0.002};
  noise.mag_world_uT = testing::kEarthField_uT;
  return noise;
}

// The case is what it claims: inside the norm and dip gates, the azimuth turned by > 15 deg.
void ExpectInsideTheGates(const Eigen::Vector3d& change_uT, const AttitudeFilterOptions& options) {
  const Eigen::Vector3d& m = testing::kEarthField_uT;
  const Eigen::Vector3d changed = m + change_uT;
  const auto dip = [](const Eigen::Vector3d& v) { return std::atan2(-v.z(), v.head<2>().norm()); };
  const auto azimuth = [](const Eigen::Vector3d& v) { return std::atan2(v.x(), v.y()); };
  EXPECT_LT(std::abs(changed.norm() / m.norm() - 1.0), options.mag_norm_tolerance);
  EXPECT_LT(std::abs(dip(changed) - dip(m)), options.mag_dip_tolerance_rad);
  EXPECT_GT(std::abs(azimuth(changed) - azimuth(m)), 15.0 * kDeg);
}

// A magnet appears (at 60 s) on a sensor that barely turns: carried level, swaying by a few
// degrees, yaw within +-0.25 rad at under 8 deg/s, shaken as by walking. Without rotation a
// body-fixed offset and a changed world field are the same thing to the data, and the field
// disagrees with the gyro's heading by ~19 deg while the filter's own heading sd is 0.5-2.2
// deg: heading must coast on the gyro, not follow the field once the disagreement has
// lasted mag_consistency_s (the rule before mag_consistency_rate_rps: 20-22 deg here).
// Scored for the 60 s after the magnet appears, where the consistency gate with the coasting
// heading's 3 sd (asserted) stays well inside the 19 deg; later that gate widens as heading
// coasts and, ~110 s after the magnet appeared on one draw, admits the field (ACCURACY.md).
// Bound 3 deg (measured 0.3-2.2: the gyro's noise and the bias error about Up). Draws: three
// noise seeds, the magnet on either side.
TEST(MagDisturbanceTest, MagnetOnASensorThatBarelyTurnsIsNotBelieved) {
  AttitudeTrajectoryOptions motion;
  motion.euler0_rad = {0.0, 0.0, 0.6};
  motion.amplitude_rad = {0.05, 0.04, 0.25};
  motion.frequency_hz = {0.31, 0.23, 0.04};
  motion.linear_amplitude_mps2 = {0.6, 0.4, 0.8};
  motion.linear_frequency_hz = 1.8;
  const AttitudeTrajectory truth(motion);
  constexpr double kArrive_s = 60.0, kEnd_s = 120.0;
  AttitudeFilterOptions options;
  options.use_mag = true;
  ExpectInsideTheGates(kAcross_uT * AcrossTheField(), options);
  const uint64_t kSeeds[] = {31, 32, 33};
  for (const uint64_t seed : kSeeds) {
    for (const double side : {1.0, -1.0}) {
      std::vector<ImuSample> samples = SynthesiseImu(truth, testing::kRateHz, kEnd_s, BiasedConsumerImu(), seed);
      BodyFixedMagnet magnet;  // across the field, in the world, as it appears
      magnet.offset_uT = truth.At(kArrive_s).conjugate() * (side * kAcross_uT * AcrossTheField());
      magnet.start_s = kArrive_s;
      AddBodyFixedMagnet(magnet, &samples);
      QuaternionEkf filter(options);
      double max_heading_rad = 0.0, max_heading_sd_rad = 0.0, max_rate_rps = 0.0;
      for (const ImuSample& s : samples) {
        ASSERT_TRUE(filter.Update(s).ok());
        max_rate_rps = std::max(max_rate_rps, truth.BodyRate(s.t_s).norm());
        if (s.t_s < kArrive_s) continue;
        const AttitudeEstimate e = filter.estimate();
        max_heading_rad = std::max(max_heading_rad, AttitudeErrorOf(e.body_to_world, truth.At(s.t_s)).heading_rad);
        max_heading_sd_rad = std::max(max_heading_sd_rad, e.world_error_sd_rad.z());
      }
      std::printf(
          "seed %lu side %+.0f: largest heading error %.2f deg, heading sd up to %.2f deg, rate up to %.1f deg/s\n",
          static_cast<unsigned long>(seed), side, max_heading_rad / kDeg, max_heading_sd_rad / kDeg,
          max_rate_rps / kDeg);
      EXPECT_LT(max_rate_rps, options.mag_consistency_rate_rps);  // it never turns fast enough to count
      // The field stays outside the consistency gate the whole time (its 3-sd part included),
      // so only the steady-disagreement timer could let it in.
      EXPECT_LT(options.mag_heading_gate_rad + 3.0 * max_heading_sd_rad, 15.0 * kDeg);
      EXPECT_LT(max_heading_rad, 3.0 * kDeg) << "seed " << seed << " side " << side;
    }
  }
}

// The other side of the rule: where the field is right and the gyro's heading is not, a
// sensor that turns lets the field back in. The same 6 µT change, fixed in the world, is
// there for the first 8 s, so the filter's first heading and norm-and-dip reference come from
// it and are 19 deg off; from 8 s on the field is the Earth's, which keeps its norm and dip
// while the sensor turns about the vertical at 0.6 rad/s (34 deg/s; the rotation about one
// axis never lets the hard-iron fit trust itself). After mag_consistency_s of turning the field
// is believed and the heading re-learnt from it: from 8 + 10 + 5 s on within 2 deg (measured
// 0.5-0.7; 3.7-13.7 when the believed field went through the ordinary gain, which moved the
// bias about Up by 0.017 rad/s and turned the heading away again). Three seeds.
TEST(MagDisturbanceTest, FieldThatStaysSteadyWhileTurningIsBelieved) {
  AttitudeTrajectoryOptions motion;
  motion.amplitude_rad = {0.1, 0.08, 0.0};
  motion.frequency_hz = {0.21, 0.17, 0.0};
  motion.euler_rate_rps = {0.0, 0.0, 0.6};
  const AttitudeTrajectory truth(motion);
  constexpr double kChangeEnds_s = 8.0, kFrom_s = 23.0, kEnd_s = 40.0;
  AttitudeFilterOptions options;
  options.use_mag = true;
  const Eigen::Vector3d change_uT = kAcross_uT * AcrossTheField();
  ExpectInsideTheGates(change_uT, options);
  ImuNoise noise = BiasedConsumerImu();
  noise.mag_disturbance_world_uT = change_uT;
  noise.disturbance_start_s = 0.0;
  noise.disturbance_end_s = kChangeEnds_s;
  for (const uint64_t seed : {41, 42, 43}) {
    const std::vector<ImuSample> samples = SynthesiseImu(truth, testing::kRateHz, kEnd_s, noise, seed);
    const testing::RunErrors early = testing::RunFilter(options, truth, samples, kChangeEnds_s);
    const testing::RunErrors late = testing::RunFilter(options, truth, samples, kFrom_s);
    std::printf("seed %lu: largest heading error from %.0f s %.2f deg, from %.0f s %.2f deg\n",
                static_cast<unsigned long>(seed), kChangeEnds_s, early.max_heading_rad / kDeg, kFrom_s,
                late.max_heading_rad / kDeg);
    EXPECT_GT(early.max_heading_rad, 15.0 * kDeg);  // the start was as wrong as claimed
    EXPECT_LT(late.max_heading_rad, 2.0 * kDeg) << "seed " << seed;
  }
}

}  // namespace
}  // namespace localizer::engine
