// localizer-cli doa's runner on WAV files of simulated plane waves: the directions in the
// CSV, what each array shape leaves empty, and the array file's use.
#include "clients/io/doa_runner.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "clients/io/array_json.h"
#include "clients/io/wav_io.h"
#include "tests/clients/test_util.h"
#include "tests/doa/plane_wave.h"

namespace localizer::io {
namespace {

using engine::Vec3;

// One second of a plane wave from `direction` on `sensors`, at 16 kHz, to a WAV file.
std::string WriteRecording(const testing::TempDir& dir, const std::vector<Vec3>& sensors, const Vec3& direction) {
  engine::testing::PlaneWaveScene scene;
  scene.sensors_m = sensors;
  scene.frame_samples = 16000;
  const std::vector<float> samples = engine::testing::PlaneWaveFrame(scene, {{direction, 1.0}}, 7);
  std::string path = dir.File("signals.wav");
  EXPECT_TRUE(WriteWavFloat(path, 16000.0, static_cast<int>(sensors.size()), 16000, samples.data()).ok());
  return path;
}

std::vector<std::vector<std::string>> ReadCsv(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::vector<std::string>> rows;
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> cells;
    std::stringstream s(line);
    for (std::string cell; std::getline(s, cell, ',');) cells.push_back(cell);
    if (!line.empty() && line.back() == ',') cells.emplace_back();
    rows.push_back(cells);
  }
  return rows;
}

TEST(DoaRunner, AFourMicrophoneBoardGivesTheDirectionInEveryFrame) {
  testing::TempDir dir;
  const double a = 0.0405;
  const std::vector<Vec3> board{Vec3(a, 0, 0), Vec3(0, a, 0), Vec3(-a, 0, 0), Vec3(0, -a, 0)};
  const Vec3 truth = engine::testing::FromAzimuthElevation(1.0, 0.5);
  DoaJob job;
  job.wav_paths = {WriteRecording(dir, board, truth)};
  job.sensors_m = board;
  job.srp.band_low_hz = 100.0;
  job.srp.band_high_hz = 7000.0;
  job.srp.source_side = Vec3::UnitZ();
  job.csv_path = dir.File("doa.csv");
  auto summary = RunDoa(job);
  ASSERT_TRUE(summary.ok()) << summary.status().ToString();
  EXPECT_EQ(summary->shape, engine::ArrayShape::kPlanar);
  EXPECT_EQ(summary->frames, (16000 - 512) / 256 + 1);

  const auto rows = ReadCsv(job.csv_path);
  ASSERT_GT(rows.size(), 1u);
  EXPECT_EQ(rows[0][0], "t_s");
  EXPECT_EQ(rows[0].size(), 11u);
  int near = 0;
  for (size_t r = 1; r < rows.size(); ++r) {
    ASSERT_EQ(rows[r].size(), 11u) << r;
    if (rows[r][1] != "0") continue;  // the strongest peak of each frame
    EXPECT_EQ(rows[r][2], "1");
    EXPECT_EQ(rows[r][5], "");  // no cone angle for a planar array
    EXPECT_EQ(rows[r][6], "");  // no mirror: the side was stated
    near += std::abs(std::stod(rows[r][3]) - 1.0) < 0.05 && std::abs(std::stod(rows[r][4]) - 0.5) < 0.05;
  }
  EXPECT_EQ(near, summary->frames);
}

TEST(DoaRunner, ALineGivesTheConeAngleOnly) {
  testing::TempDir dir;
  std::vector<Vec3> line;
  for (int k = 0; k < 8; ++k) line.push_back(Vec3(0.04 * k, 0, 0));
  const Vec3 truth = engine::testing::FromAzimuthElevation(0.8, 0.3);  // cone angle acos(x)
  DoaJob job;
  job.wav_paths = {WriteRecording(dir, line, truth)};
  job.sensors_m = line;
  job.srp.band_low_hz = 100.0;
  job.srp.band_high_hz = 7000.0;
  job.csv_path = dir.File("doa.csv");
  auto summary = RunDoa(job);
  ASSERT_TRUE(summary.ok()) << summary.status().ToString();
  EXPECT_EQ(summary->shape, engine::ArrayShape::kLinear);
  const auto rows = ReadCsv(job.csv_path);
  for (size_t r = 1; r < rows.size(); ++r) {
    if (rows[r][1] != "0") continue;
    EXPECT_EQ(rows[r][3], "");
    EXPECT_EQ(rows[r][4], "");
    EXPECT_NEAR(std::stod(rows[r][5]), std::acos(truth.x()), 0.03) << rows[r][0];
  }
}

TEST(DoaRunner, APlanarArrayFileIsForDirectionsNotPositions) {
  testing::TempDir dir;
  const std::string path = dir.File("board.json");
  std::ofstream(path) << R"({"sound_speed_mps": 343, "sensors_m": [[0.04,0,0],[0,0.04,0],[-0.04,0,0],[0,-0.04,0]]})";
  const Status for_positions = ReadArrayJson(path).status();
  EXPECT_EQ(for_positions.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(for_positions.message().find("board.json"), std::string::npos) << for_positions.message();
  EXPECT_TRUE(ReadArrayJson(path, ArrayUse::kDirection).ok());
  std::ofstream(path) << R"({"sound_speed_mps": 343, "sensors_m": [[0,0,0]]})";
  EXPECT_EQ(ReadArrayJson(path, ArrayUse::kDirection).status().code(), StatusCode::kInvalidArgument);
}

TEST(DoaRunner, AChannelCountThatIsNotTheArraysIsNamed) {
  testing::TempDir dir;
  const std::vector<Vec3> pair{Vec3::Zero(), Vec3(0.1, 0, 0)};
  DoaJob job;
  job.wav_paths = {WriteRecording(dir, pair, Vec3::UnitX())};
  job.sensors_m = {Vec3::Zero(), Vec3(0.1, 0, 0), Vec3(0, 0.1, 0)};
  job.array_source = "three.json";
  job.csv_path = dir.File("doa.csv");
  const Status s = RunDoa(job).status();
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("three.json has 3 sensors"), std::string::npos) << s.message();
}

}  // namespace
}  // namespace localizer::io
