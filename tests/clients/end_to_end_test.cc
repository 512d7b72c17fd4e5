// simulate -> track -> score through the functions the localizer-cli commands call
// (io::SimulateScenario, WriteSimulationFiles, RunTrack, the CSV readers and Score), on
// the files they write. A test cannot link the executable itself; the commands only add
// flag parsing and printing around these calls.
#include <gtest/gtest.h>

#include <fstream>
#include <optional>

#include "clients/io/array_json.h"
#include "clients/io/csv_io.h"
#include "clients/io/score.h"
#include "clients/io/simulation_files.h"
#include "clients/io/track_runner.h"
#include "clients/io/wav_io.h"
#include "tests/clients/test_util.h"

namespace localizer::io {
namespace {

using testing::FirstLine;
using testing::TempDir;

// Callbacks that collect the warnings RunTrack reports.
TrackCallbacks CollectWarnings(std::vector<std::string>* warnings) {
  TrackCallbacks callbacks;
  callbacks.on_warning = [warnings](const std::string& w) { warnings->push_back(w); };
  return callbacks;
}

// `track` as the CLI builds it: array from array.json, sample rate from the WAV.
TrackJob JobFor(const SimulationFiles& files, const ArrayFile& array, const std::string& out) {
  TrackJob job;
  job.wav_paths = {files.wav_path};
  job.array_source = files.array_path;
  job.array_sample_rate_hz = array.sample_rate_hz;
  job.config.sensors_m = array.sensors_m;
  job.config.sound_speed_mps = array.sound_speed_mps;
  job.config.reference_sensor = array.reference_sensor;
  job.estimates_path = out;
  return job;
}

TEST(EndToEnd, SimulateWritesTheThreeFiles) {
  TempDir dir;
  auto run = SimulateScenario("tetra-water", 1, 6.0);
  ASSERT_TRUE(run.ok()) << run.status().ToString();
  auto files = WriteSimulationFiles(dir.File("sim"), *run);
  ASSERT_TRUE(files.ok()) << files.status().ToString();

  auto wav = ReadWav(files->wav_path);
  ASSERT_TRUE(wav.ok()) << wav.status().ToString();
  EXPECT_EQ(wav->channel_count, 4);
  EXPECT_EQ(wav->sample_rate_hz, 11025.0);
  EXPECT_EQ(wav->frames, 6 * 11025);
  EXPECT_EQ(wav->samples, run->result.samples);  // float32 WAV keeps the simulation exactly

  auto array = ReadArrayJson(files->array_path);
  ASSERT_TRUE(array.ok()) << array.status().ToString();
  EXPECT_EQ(array->sensors_m, run->scenario.sensors_m);
  EXPECT_EQ(array->sound_speed_mps, 1500.0);
  EXPECT_EQ(array->sample_rate_hz, 11025.0);

  EXPECT_EQ(FirstLine(files->truth_path), "t_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps");
  auto truth = ReadTruthCsv(files->truth_path);
  ASSERT_TRUE(truth.ok()) << truth.status().ToString();
  EXPECT_EQ(truth->size(), run->result.truth.size());
}

TEST(EndToEnd, TetraWaterTracksBelowOneMetreRmse) {
  TempDir dir;
  auto run = SimulateScenario("tetra-water", 1, 6.0);
  ASSERT_TRUE(run.ok()) << run.status().ToString();
  auto files = WriteSimulationFiles(dir.path().string(), *run);
  ASSERT_TRUE(files.ok()) << files.status().ToString();
  auto array = ReadArrayJson(files->array_path);
  ASSERT_TRUE(array.ok()) << array.status().ToString();

  TrackJob job = JobFor(*files, *array, dir.File("estimates.csv"));
  std::vector<std::string> warnings;
  auto summary = RunTrack(job, CollectWarnings(&warnings));
  ASSERT_TRUE(summary.ok()) << summary.status().ToString();
  EXPECT_TRUE(warnings.empty());
  EXPECT_EQ(summary->estimates, (6u * 11025 - 4096) / 2048 + 1);

  EXPECT_EQ(FirstLine(job.estimates_path),
            "t_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,sx_m,sy_m,sz_m,ess,nis,pairs_used,tdoa_sigma_us,initialised,"
            "reinitialised,tdoa_ms,filter_ms,source_present,presence_statistic,presence_threshold,ambiguous,modes,far_field,range_sd_m,"
            "delay_s_1,quality_1,delay_s_2,quality_2,"
            "delay_s_3,quality_3");
  auto truth = ReadTruthCsv(files->truth_path);
  ASSERT_TRUE(truth.ok());
  auto estimates = ReadEstimatesCsv(job.estimates_path);
  ASSERT_TRUE(estimates.ok()) << estimates.status().ToString();
  auto score = Score(*truth, *estimates);
  ASSERT_TRUE(score.ok()) << score.status().ToString();
  std::printf("tetra-water 6 s: %s\n", FormatScore(*score).c_str());
  EXPECT_GE(score->count, 25);
  EXPECT_LT(score->rmse_m, 1.0);
}

// One second of tetra-water written to `dir`, and its array.json read back.
void SimulateOneSecond(const TempDir& dir, std::optional<SimulationFiles>* files, std::optional<ArrayFile>* array) {
  auto run = SimulateScenario("tetra-water", 1, 1.0);
  ASSERT_TRUE(run.ok());
  auto written = WriteSimulationFiles(dir.path().string(), *run);
  ASSERT_TRUE(written.ok());
  auto read = ReadArrayJson(written->array_path);
  ASSERT_TRUE(read.ok());
  *files = *written;
  *array = *read;
}

TEST(EndToEnd, TrackRejectsAChannelCountThatDoesNotMatchTheArray) {
  TempDir dir;
  std::optional<SimulationFiles> files;
  std::optional<ArrayFile> array;
  ASSERT_NO_FATAL_FAILURE(SimulateOneSecond(dir, &files, &array));
  array->sensors_m.push_back(engine::Vec3(3, 3, -12));  // 5 sensors, 4 channels
  auto summary = RunTrack(JobFor(*files, *array, ""));
  ASSERT_FALSE(summary.ok());
  EXPECT_NE(summary.status().message().find("has 4 channels but"), std::string::npos) << summary.status().message();
  EXPECT_NE(summary.status().message().find("5 sensors"), std::string::npos);
}

TEST(EndToEnd, WavRateWinsOverArrayJsonWithAWarning) {
  TempDir dir;
  std::optional<SimulationFiles> files;
  std::optional<ArrayFile> array;
  ASSERT_NO_FATAL_FAILURE(SimulateOneSecond(dir, &files, &array));
  array->sample_rate_hz = 8000.0;
  std::vector<std::string> warnings;
  auto summary = RunTrack(JobFor(*files, *array, ""), CollectWarnings(&warnings));
  ASSERT_TRUE(summary.ok()) << summary.status().ToString();
  EXPECT_EQ(summary->sample_rate_hz, 11025.0);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("using the WAV header's rate"), std::string::npos);
}

}  // namespace
}  // namespace localizer::io
