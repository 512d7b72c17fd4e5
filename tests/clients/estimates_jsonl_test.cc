// track --format jsonl (issue 19): one JSON object per estimate, numbers that read back
// exactly, null for what JSON cannot hold, and the same track as the CSV of the same run.
#include "clients/io/estimates_jsonl.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "clients/io/array_json.h"
#include "clients/io/csv_io.h"
#include "clients/io/simulation_files.h"
#include "clients/io/track_runner.h"
#include "tests/clients/test_util.h"

namespace localizer::io {
namespace {

using nlohmann::json;
using testing::TempDir;

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

engine::Estimate Initialised() {
  engine::Estimate e;
  e.frame_index = 7;
  e.t_s = 1.0 / 3.0;  // no short decimal: must still read back exactly
  e.initialised = true;
  e.source_present = true;
  e.presence_statistic = 9.5;
  e.presence_threshold = 5.25;
  e.state << 1.5, -2.25, -8.125, 0.5, 0.0, -0.1;
  e.covariance = engine::Mat6::Identity() * 0.04;
  e.covariance(0, 1) = e.covariance(1, 0) = 0.01;
  e.delay_s = {1e-3, kNan, -2.5e-4};
  e.quality = {12.0, 0.0, 3.5};
  e.pairs_used = 2;
  return e;
}

TEST(EstimatesJsonl, OneObjectWithExactNumbersAndNullForNonFinite) {
  const engine::Estimate e = Initialised();
  const std::string line = EstimateJsonLine(e, {1, 2, 3});
  EXPECT_EQ(line.find('\n'), std::string::npos);
  const json j = json::parse(line);
  EXPECT_EQ(j.at("frame"), 7);
  EXPECT_EQ(j.at("t_s").get<double>(), 1.0 / 3.0);
  EXPECT_EQ(j.at("initialised"), true);
  EXPECT_EQ(j.at("source_present"), true);
  EXPECT_EQ(j.at("position_m"), json::array({1.5, -2.25, -8.125}));
  EXPECT_EQ(j.at("velocity_mps"), json::array({0.5, 0.0, -0.1}));
  EXPECT_DOUBLE_EQ(j.at("position_sd_m")[0].get<double>(), 0.2);
  EXPECT_EQ(j.at("covariance")[0][1].get<double>(), 0.01);
  ASSERT_EQ(j.at("pairs").size(), 3u);
  EXPECT_EQ(j.at("pairs")[0].at("sensor"), 1);
  EXPECT_EQ(j.at("pairs")[0].at("delay_s").get<double>(), 1e-3);
  EXPECT_TRUE(j.at("pairs")[1].at("delay_s").is_null()) << "NaN must be null";
  EXPECT_EQ(j.at("pairs")[2].at("quality").get<double>(), 3.5);
  EXPECT_FALSE(j.contains("sources"));
  EXPECT_FALSE(j.contains("model_probabilities"));
}

TEST(EstimatesJsonl, NotInitialisedHasNoPositionAndSourcesNest) {
  engine::Estimate e;
  e.frame_index = 0;
  e.range_sd_m = std::numeric_limits<double>::infinity();
  engine::SourceEstimate line_source;
  line_source.source_id = 3;
  line_source.status = engine::TrackStatus::kConfirmed;
  line_source.cone_angle_rad = 0.75;
  line_source.source_present = true;
  e.sources = {line_source};
  const json j = json::parse(EstimateJsonLine(e, {}));
  EXPECT_FALSE(j.contains("position_m"));
  EXPECT_FALSE(j.contains("covariance"));
  EXPECT_TRUE(j.at("range_sd_m").is_null()) << "infinity must be null";
  ASSERT_EQ(j.at("sources").size(), 1u);
  const json& s = j.at("sources")[0];
  EXPECT_EQ(s.at("source_id"), 3);
  EXPECT_EQ(s.at("status"), "confirmed");
  EXPECT_EQ(s.at("cone_angle_rad").get<double>(), 0.75);
  EXPECT_TRUE(s.at("azimuth_rad").is_null()) << "a line has no azimuth";
  EXPECT_TRUE(s.at("position_m").is_null());
}

TEST(EstimatesJsonl, FormatNamesAreParsedAndUnknownOnesRefused) {
  EXPECT_EQ(*ParseEstimatesFormat("csv"), EstimatesFormat::kCsv);
  EXPECT_EQ(*ParseEstimatesFormat("jsonl"), EstimatesFormat::kJsonl);
  const auto bad = ParseEstimatesFormat("xml");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("csv, jsonl"), std::string::npos) << bad.status().message();
  EXPECT_FALSE(EstimatesJsonlWriter::Open("/nonexistent-dir/e.jsonl", {}).ok());
}

// The same run written both ways: one line per CSV row, the same instants and positions
// (the CSV prints 9 significant digits; JSON round-trips doubles).
TEST(EstimatesJsonl, RunTrackWritesTheSameTrackAsTheCsv) {
  TempDir dir;
  auto run = SimulateScenario("tetra-water", 1, 3.0);
  ASSERT_TRUE(run.ok()) << run.status().ToString();
  auto files = WriteSimulationFiles(dir.path().string(), *run);
  ASSERT_TRUE(files.ok()) << files.status().ToString();
  auto array = ReadArrayJson(files->array_path);
  ASSERT_TRUE(array.ok()) << array.status().ToString();
  TrackJob job;
  job.wav_paths = {files->wav_path};
  job.array_source = files->array_path;
  job.array_sample_rate_hz = array->sample_rate_hz;
  job.config.sensors_m = array->sensors_m;
  job.config.sound_speed_mps = array->sound_speed_mps;
  job.estimates_path = dir.File("e.csv");
  ASSERT_TRUE(RunTrack(job).ok());
  job.estimates_path = dir.File("e.jsonl");
  job.estimates_format = EstimatesFormat::kJsonl;
  ASSERT_TRUE(RunTrack(job).ok());

  auto csv = ReadEstimatesCsv(dir.File("e.csv"));
  ASSERT_TRUE(csv.ok()) << csv.status().ToString();
  std::ifstream in(dir.File("e.jsonl"));
  std::string line;
  size_t row = 0;
  while (std::getline(in, line)) {
    ASSERT_LT(row, csv->size());
    const json j = json::parse(line);
    const EstimateRow& r = (*csv)[row];
    EXPECT_NEAR(j.at("t_s").get<double>(), r.t_s, 1e-8 * std::abs(r.t_s) + 1e-12);
    EXPECT_EQ(j.at("initialised").get<bool>(), r.initialised);
    if (r.initialised) {
      for (int axis = 0; axis < 3; ++axis) {
        EXPECT_NEAR(j.at("position_m")[axis].get<double>(), r.position_m[axis], 1e-7 * (1.0 + std::abs(r.position_m[axis])))
            << "row " << row << " axis " << axis;
      }
    }
    ++row;
  }
  EXPECT_EQ(row, csv->size());
  EXPECT_GT(row, 10u);
}

}  // namespace
}  // namespace localizer::io
