// The real XAV hydrophone recordings (Mouy et al. 2023, BSD 3-Clause) load as documented.
#include <gtest/gtest.h>

#include <cmath>

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

// The water column constants agree with the authors' deployment sheet: every hydrophone's
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
    EXPECT_NEAR(*sheet->Number(r, *depth), kXavSurfaceZM - xav->array.sensors_m[k].z(), 0.005) << "channel " << k;
    EXPECT_EQ(*sheet->Number(r, *water), kXavWaterDepthM);
  }
  EXPECT_EQ(xav->array.bounds_max_m.z(), kXavSurfaceZM);
  EXPECT_DOUBLE_EQ(xav->array.bounds_min_m.z(), -0.97);
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
