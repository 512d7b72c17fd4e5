// The batched GPU SRP-PHAT (gpu/srp/srp_batch.h) against the CPU's engine::SrpPhat on the same
// frames: the device map equals SrpPhat::Statistic at every grid direction within
// kSrpMapToleranceZ, the arg-max and the refined peak are the CPU's, for sessions of several
// arrays in one batch (and for spectra that need the map kernel's opt-in shared memory). Tests that need a device skip with the reason where there is none; the
// configuration checks run everywhere.
#include "gpu/srp/srp_batch.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "gpu/srp/srp_grid.h"
#include "gpu/srp/srp_kernels.h"
#include "tests/gpu/gpu_test_util.h"
#include "tests/gpu/srp_test_scenes.h"

namespace localizer::gpu {
namespace {

using engine::Vec3;

SrpArrayConfig ConfigFor(const std::vector<Vec3>& sensors, int frame_samples = 256) {
  SrpArrayConfig c;
  c.sensors_m = sensors;
  c.options = testing::FrameOptions(frame_samples);
  StatusOr<SrpArrayModel> model = MakeSrpArrayModel(sensors, c.options);
  EXPECT_TRUE(model.ok()) << model.status().ToString();
  c.directions = CpuLikeGrid(*model);
  return c;
}

TEST(SrpBatch, CreateRejectsBadConfigurationsWithOrWithoutADevice) {
  EXPECT_EQ(SrpBatch::Create({}, 8).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(SrpBatch::Create({ConfigFor(testing::Respeaker4())}, 0).status().code(), StatusCode::kInvalidArgument);
  SrpArrayConfig empty = ConfigFor(testing::Respeaker4());
  empty.directions.clear();
  EXPECT_EQ(SrpBatch::Create({empty}, 8).status().code(), StatusCode::kInvalidArgument);
  SrpArrayConfig nan = ConfigFor(testing::Respeaker4());
  nan.directions[3] = Vec3(std::nan(""), 0, 0);
  const Status bad_direction = SrpBatch::Create({nan}, 8).status();
  EXPECT_EQ(bad_direction.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(bad_direction.message().find("direction 3"), std::string::npos) << bad_direction.message();
  SrpArrayConfig one_sensor = ConfigFor(testing::Respeaker4());
  one_sensor.sensors_m.resize(1);
  const Status bad_array = SrpBatch::Create({ConfigFor(testing::Tetra4()), one_sensor}, 8).status();
  EXPECT_EQ(bad_array.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(bad_array.message().find("array 1"), std::string::npos) << bad_array.message();
}

TEST(SrpBatch, WithoutADeviceCreateIsAFailedPrecondition) {
  if (testing::GpuSkipReason().empty()) GTEST_SKIP() << "a device is usable here";
  EXPECT_EQ(SrpBatch::Create({ConfigFor(testing::Respeaker4())}, 8).status().code(),
            StatusCode::kFailedPrecondition);
}

struct Session {
  int array = 0;
  Vec3 direction;
  std::unique_ptr<engine::SrpPhat> cpu;
  std::vector<engine::DirectionPeak> peaks;
  std::vector<std::complex<float>> spectra;
};

// Sessions over `arrays` in turn, each a seeded plane wave analysed by its own CPU SrpPhat.
std::vector<Session> MakeSessions(const std::vector<SrpArrayConfig>& arrays, int count, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<Session> sessions;
  for (int s = 0; s < count; ++s) {
    Session session;
    session.array = s % static_cast<int>(arrays.size());
    const SrpArrayConfig& config = arrays[static_cast<size_t>(session.array)];
    session.direction = Vec3(n(rng), n(rng), n(rng)).normalized();
    StatusOr<engine::SrpPhat> cpu = engine::SrpPhat::Create(config.sensors_m, config.options);
    EXPECT_TRUE(cpu.ok());
    session.cpu = std::make_unique<engine::SrpPhat>(std::move(*cpu));
    const std::vector<float> frame =
        testing::PlaneWave(config.sensors_m, config.options, session.direction, 0.5 + s % 4, seed * 1000 + s);
    StatusOr<std::vector<engine::DirectionPeak>> peaks = session.cpu->Analyse(frame.data());
    EXPECT_TRUE(peaks.ok());
    session.peaks = *peaks;
    StatusOr<SrpArrayModel> model = MakeSrpArrayModel(config.sensors_m, config.options);
    session.spectra = testing::AsFloat(testing::RecoveredSpectra(*session.cpu, *model));
    sessions.push_back(std::move(session));
  }
  return sessions;
}

// Runs `count` sessions over `arrays` in one batch and holds every map value, arg-max and peak
// to the CPU's.
void ExpectTheCpusMapsAndPeaks(const std::vector<SrpArrayConfig>& arrays, int count, uint64_t seed) {
  auto batch = SrpBatch::Create(arrays, 64);
  ASSERT_TRUE(batch.ok()) << batch.status().ToString();
  std::vector<Session> sessions = MakeSessions(arrays, count, seed);
  std::vector<SrpPeak> peaks(sessions.size());
  std::vector<std::vector<float>> maps(sessions.size());
  std::vector<SrpJob> jobs;
  for (size_t s = 0; s < sessions.size(); ++s)
    jobs.push_back({sessions[s].array, sessions[s].spectra.data(), &peaks[s], &maps[s]});
  ASSERT_TRUE((*batch)->Run(jobs).ok());
  double worst_z = 0.0, worst_rad = 0.0;
  for (size_t s = 0; s < sessions.size(); ++s) {
    const Session& session = sessions[s];
    const std::vector<Vec3>& grid = (*batch)->directions(session.array);
    ASSERT_EQ(maps[s].size(), grid.size());
    std::vector<double> cpu;
    for (size_t d = 0; d < grid.size(); ++d) {
      cpu.push_back(session.cpu->Statistic(grid[d]));
      worst_z = std::max(worst_z, std::abs(maps[s][d] - cpu.back()));
      ASSERT_NEAR(maps[s][d], cpu.back(), kSrpMapToleranceZ) << "session " << s << " direction " << d;
    }
    const size_t cpu_best = static_cast<size_t>(std::max_element(cpu.begin(), cpu.end()) - cpu.begin());
    ASSERT_GE(peaks[s].grid_index, 0);
    EXPECT_LE(cpu[cpu_best] - cpu[static_cast<size_t>(peaks[s].grid_index)], 2.0 * kSrpMapToleranceZ) << "session " << s;
    ASSERT_EQ(session.peaks.size(), 1u);
    const engine::DirectionPeak& want = session.peaks[0];
    double error = 0.0;
    if (std::isnan(want.direction.x())) {
      error = std::abs(peaks[s].cone_angle_rad - want.cone_angle_rad);
    } else {
      error = testing::AngleRad(peaks[s].direction, want.direction);
    }
    EXPECT_LT(error, kSrpDirectionToleranceRad) << "session " << s;
    worst_rad = std::max(worst_rad, error);
    EXPECT_NEAR(peaks[s].statistic, want.statistic, kSrpStatisticToleranceRelative * want.statistic) << "session " << s;
    EXPECT_EQ(peaks[s].mirror_ambiguous, want.mirror_ambiguous) << "session " << s;
    EXPECT_EQ(peaks[s].threshold, want.threshold);
  }
  std::printf("device map vs SrpPhat::Statistic: max |dz| %.3g (tolerance %.1g); refined vs CPU Analyse: max %.3g rad\n",
              worst_z, kSrpMapToleranceZ, worst_rad);
}

TEST(SrpBatch, DeviceMapAndPeakEqualTheCpuForSessionsOfFourArrays) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  ExpectTheCpusMapsAndPeaks({ConfigFor(testing::Respeaker4()), ConfigFor(testing::Tetra4()),
                             ConfigFor(testing::Line8()), ConfigFor(testing::RandomArray(6, 0.1, 66))},
                            24, 3);
}

// 28 pairs of 1024-sample frames: ~100 KiB of spectra per session, past the 48 KiB a block gets
// without opting in (PrepareSrpMap raises the map kernel's limit).
TEST(SrpBatch, SpectraBeyond48KiBPerSessionUseTheOptInSharedMemory) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  const SrpArrayConfig line = ConfigFor(testing::Line8(), 1024), cube = ConfigFor(testing::RandomArray(8, 0.1, 88), 1024);
  StatusOr<SrpArrayModel> model = MakeSrpArrayModel(line.sensors_m, line.options);
  ASSERT_TRUE(model.ok());
  EXPECT_GT(SrpMapSharedBytes(model->spectrum_floats(), model->pairs), 48 * 1024);
  ExpectTheCpusMapsAndPeaks({line, cube}, 8, 4);
}

TEST(SrpBatch, ASessionsResultDoesNotDependOnItsBatch) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  const std::vector<SrpArrayConfig> arrays = {ConfigFor(testing::Respeaker4()), ConfigFor(testing::Circle7())};
  auto batch = SrpBatch::Create(arrays, 64);
  ASSERT_TRUE(batch.ok()) << batch.status().ToString();
  std::vector<Session> sessions = MakeSessions(arrays, 37, 5);
  std::vector<SrpPeak> together(sessions.size()), alone(1);
  std::vector<SrpJob> jobs;
  for (size_t s = 0; s < sessions.size(); ++s) jobs.push_back({sessions[s].array, sessions[s].spectra.data(), &together[s]});
  ASSERT_TRUE((*batch)->Run(jobs).ok());
  for (size_t s = 0; s < sessions.size(); s += 6) {
    const SrpJob one{sessions[s].array, sessions[s].spectra.data(), &alone[0]};
    ASSERT_TRUE((*batch)->Run({&one, 1}).ok());
    EXPECT_EQ(alone[0].grid_index, together[s].grid_index);
    EXPECT_EQ(alone[0].statistic, together[s].statistic);  // bit for bit
    EXPECT_EQ(alone[0].direction, together[s].direction);
  }
}

TEST(SrpBatch, RunRejectsBadJobsBeforeAnyWork) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  auto batch = SrpBatch::Create({ConfigFor(testing::Respeaker4())}, 4);
  ASSERT_TRUE(batch.ok()) << batch.status().ToString();
  std::vector<Session> sessions = MakeSessions({ConfigFor(testing::Respeaker4())}, 2, 8);
  SrpPeak out;
  EXPECT_EQ((*batch)->Run({}).code(), StatusCode::kInvalidArgument);
  const SrpJob wrong_array{1, sessions[0].spectra.data(), &out};
  EXPECT_EQ((*batch)->Run({&wrong_array, 1}).code(), StatusCode::kInvalidArgument);
  std::vector<std::complex<float>> poisoned = sessions[1].spectra;
  poisoned[17] = {std::nanf(""), 0.0f};
  const SrpJob jobs[2] = {{0, sessions[0].spectra.data(), &out}, {0, poisoned.data(), &out}};
  const Status status = (*batch)->Run(jobs);
  EXPECT_EQ(status.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(status.message().find("job 1"), std::string::npos) << status.message();
  std::vector<SrpJob> too_many(5, jobs[0]);
  EXPECT_EQ((*batch)->Run(too_many).code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace localizer::gpu
