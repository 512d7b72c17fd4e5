// The real XAV hydrophone recordings (Mouy et al. 2023, BSD 3-Clause) load as documented.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "clients/io/csv_table.h"
#include "clients/io/wav_io.h"
#include "clients/io/xav_array.h"
#include "tests/clients/test_util.h"

namespace localizer::io {
namespace {

std::vector<std::string> XavPaths() {
  auto xav = ReadXavHydrophoneCsv(testing::XavConfigCsv());
  EXPECT_TRUE(xav.ok()) << xav.status().ToString();
  if (!xav.ok()) return {};
  auto paths = FindXavRecordings(testing::XavDir(), xav->file_name_roots);
  EXPECT_TRUE(paths.ok()) << paths.status().ToString();
  return paths.ok() ? *paths : std::vector<std::string>{};
}

TEST(XavData, HydrophoneConfigGivesSixSensorsAndTheirFiles) {
  auto xav = ReadXavHydrophoneCsv(testing::XavConfigCsv());
  ASSERT_TRUE(xav.ok()) << xav.status().ToString();
  ASSERT_EQ(xav->array.sensors_m.size(), 6u);
  EXPECT_EQ(xav->array.sensors_m[0], engine::Vec3(-0.858, -0.86, -0.671));
  EXPECT_EQ(xav->file_name_roots[3], "AMAR173.4.");
  const std::vector<std::string> paths = XavPaths();
  ASSERT_EQ(paths.size(), 6u);
  EXPECT_NE(paths[0].find("AMAR173.1."), std::string::npos);
  EXPECT_NE(paths[5].find("AMAR173.6."), std::string::npos);
}

// The water column read from the authors' deployment sheet: every hydrophone's
// depth is surface_z - z (z up), and the bottom lies the water depth below the surface.
TEST(XavData, WaterColumnBoundsMatchTheDeploymentSheet) {
  auto xav = ReadXavHydrophoneCsv(testing::XavConfigCsv());
  ASSERT_TRUE(xav.ok()) << xav.status().ToString();
  auto sheet = CsvTable::Read(testing::XavDir() + "/deployment_info.csv");
  ASSERT_TRUE(sheet.ok()) << sheet.status().ToString();
  auto channel = sheet->Column("audio_channel_number");
  auto depth = sheet->Column("hydrophone_depth");
  auto water = sheet->Column("location_water_depth");
  ASSERT_TRUE(channel.ok() && depth.ok() && water.ok());
  ASSERT_EQ(sheet->row_count(), 6u);
  for (size_t r = 0; r < sheet->row_count(); ++r) {
    const int k = static_cast<int>(*sheet->Number(r, *channel));
    ASSERT_GE(k, 0);
    ASSERT_LT(k, 6);
    EXPECT_NEAR(*sheet->Number(r, *depth), xav->surface_z_m - xav->array.sensors_m[k].z(), 0.005) << "channel " << k;
    EXPECT_EQ(*sheet->Number(r, *water), xav->water_depth_m);
  }
  EXPECT_EQ(xav->water_depth_m, 8.0);
  EXPECT_NEAR(xav->surface_z_m, 7.03, 0.005);
  EXPECT_EQ(xav->array.bounds_max_m.z(), xav->surface_z_m);
  EXPECT_NEAR(xav->array.bounds_min_m.z(), -0.97, 0.005);
  for (const engine::Vec3& s : xav->array.sensors_m) {
    EXPECT_GT(s.z(), xav->array.bounds_min_m.z());
    EXPECT_LT(s.z(), xav->array.bounds_max_m.z());
  }
}

TEST(XavData, EachRecordingIs32kHzMonoAbout17sFiniteAndNotSilent) {
  for (const std::string& path : XavPaths()) {
    auto r = ReadWav(path);
    ASSERT_TRUE(r.ok()) << r.status().ToString();
    EXPECT_EQ(r->sample_rate_hz, 32000.0) << path;
    EXPECT_EQ(r->channel_count, 1) << path;
    const double seconds = static_cast<double>(r->frames) / r->sample_rate_hz;
    EXPECT_GT(seconds, 16.0) << path;
    EXPECT_LT(seconds, 18.0) << path;
    double sum_sq = 0.0;
    bool finite = true;
    for (float x : r->samples) {
      finite = finite && std::isfinite(x);
      sum_sq += double(x) * x;
    }
    EXPECT_TRUE(finite) << path;
    const double rms = std::sqrt(sum_sq / static_cast<double>(r->frames));
    EXPECT_GT(rms, 1e-5) << path << ": silent (rms " << rms << ")";
    EXPECT_LT(rms, 1.0) << path;
  }
}

TEST(XavData, TheSixFilesFormOneSixChannelRecording) {
  std::string warning;
  auto set = ReadWavSet(XavPaths(), &warning);
  ASSERT_TRUE(set.ok()) << set.status().ToString();
  EXPECT_EQ(set->channel_count, 6);
  EXPECT_EQ(set->samples.size(), static_cast<size_t>(6 * set->frames));
  // AMAR173.1 is 230 samples longer than the others: truncated, with a note.
  EXPECT_NE(warning.find("truncated"), std::string::npos) << warning;
}

}  // namespace
}  // namespace localizer::io

namespace localizer::io {
namespace {

// The deployment's files are read for what they say: the authors' values, and other values
// in a copy of the folder are taken up; a missing or bad file is refused naming it.
TEST(XavData, SoundSpeedReferenceAndRateComeFromTheDeploymentFiles) {
  auto xav = ReadXavHydrophoneCsv(testing::XavConfigCsv());
  ASSERT_TRUE(xav.ok()) << xav.status().ToString();
  EXPECT_EQ(xav->array.sound_speed_mps, 1484.0);
  EXPECT_EQ(xav->array.reference_sensor, 3);
  EXPECT_EQ(xav->array.sample_rate_hz, 32000.0);

  testing::TempDir dir;
  namespace fs = std::filesystem;
  const fs::path src(testing::XavDir());
  fs::copy_file(src / "hydrophones_config_07-HI.csv", dir.File("hydrophones.csv"));
  fs::copy_file(src / "deployment_info.csv", dir.File("deployment_info.csv"));
  const auto write_yaml = [&](const std::string& text) {
    std::ofstream(dir.File("localization_config_copy.yaml")) << text;
  };
  write_yaml("ENVIRONMENT:\n    sound_speed_mps: 1500\nTDOA:\n    ref_channel: 2\n");
  auto copy = ReadXavHydrophoneCsv(dir.File("hydrophones.csv"));
  ASSERT_TRUE(copy.ok()) << copy.status().ToString();
  EXPECT_EQ(copy->array.sound_speed_mps, 1500.0);
  EXPECT_EQ(copy->array.reference_sensor, 2);

  write_yaml("ENVIRONMENT:\n    sound_speed_mps: 1500\nTDOA:\n    ref_channel: 9\n");
  auto bad_ref = ReadXavHydrophoneCsv(dir.File("hydrophones.csv"));
  ASSERT_FALSE(bad_ref.ok());
  EXPECT_NE(bad_ref.status().message().find("TDOA.ref_channel 9"), std::string::npos) << bad_ref.status().message();

  write_yaml("ENVIRONMENT:\n    sound_speed: 1500\n");
  auto missing_key = ReadXavHydrophoneCsv(dir.File("hydrophones.csv"));
  ASSERT_FALSE(missing_key.ok());
  EXPECT_NE(missing_key.status().message().find("ENVIRONMENT.sound_speed_mps missing"), std::string::npos)
      << missing_key.status().message();

  fs::remove(dir.File("localization_config_copy.yaml"));
  auto no_yaml = ReadXavHydrophoneCsv(dir.File("hydrophones.csv"));
  ASSERT_FALSE(no_yaml.ok());
  EXPECT_EQ(no_yaml.status().code(), StatusCode::kNotFound);
  EXPECT_NE(no_yaml.status().message().find("localization_config*.yaml"), std::string::npos)
      << no_yaml.status().message();
}

}  // namespace
}  // namespace localizer::io
