// Room scene files (clients/io/room_scene_files.h): the scene file is read with every error
// naming the file and field, and simulate's four files say what was rendered where.
#include "clients/io/room_scene_files.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "clients/io/csv_table.h"
#include "clients/io/wav_io.h"
#include "tests/clients/test_util.h"

namespace localizer::io {
namespace {

using testing::TempDir;

const char* const kScene = R"({
  "room": {"size_m": [6, 5, 3], "rt60_s": 0.2},
  "array_position_m": [2.2, 1.9, 1.0],
  "duration_s": 1.5,
  "sources": [{"position_m": [4.0, 2.4, 1.4], "signal": "broadband", "band_hz": [200, 6000]},
              {"position_m": [2.7, 3.8, 1.35]}]
})";

TEST(RoomSceneFiles, ASceneIsReadWithItsDefaults) {
  auto file = ParseRoomSceneJson(kScene, "scene.json");
  ASSERT_TRUE(file.ok()) << file.status().ToString();
  EXPECT_EQ(file->array_position_m, engine::Vec3(2.2, 1.9, 1.0));
  EXPECT_DOUBLE_EQ(file->scene.room.rt60_s, 0.2);
  EXPECT_DOUBLE_EQ(file->scene.sample_rate_hz, 16000.0);
  ASSERT_EQ(file->scene.sources.size(), 2u);
  EXPECT_EQ(file->scene.sources[0].signal, engine::RoomSignal::kBroadband);
  EXPECT_DOUBLE_EQ(file->scene.sources[0].band_low_hz, 200.0);
  EXPECT_EQ(file->scene.sources[1].signal, engine::RoomSignal::kBursts);  // the default
}

TEST(RoomSceneFiles, BadFieldsAreNamed) {
  for (const auto& [text, expected] : std::vector<std::pair<std::string, std::string>>{
           {R"({"sources": []})", "missing required field room"},
           {R"({"room": {"size_m": [6, 5, 3]}, "sources": [], "colour": 1})", "unknown field \"colour\""},
           {R"({"room": {"size_m": [6, 5]}, "sources": []})", "room.size_m must be [x, y, z]"},
           {R"({"room": {"size_m": [6, 5, 3]}, "sources": [{"signal": "bursts"}]})", "sources[0] needs position_m"},
           {R"({"room": {"size_m": [6, 5, 3]}, "sources": [{"position_m": [1, 1, 1], "signal": "whisper"}]})",
            "sources[0].signal"},
           {R"({"room": {"size_m": [6, 5, 3]}, "sources": [{"position_m": [1, 1, 1], "on_s": 1}]})",
            "sources[0].on_s must be [low, high]"},
           {R"({"room": {"size_m": [6, 5, 3]}, "sources": 3})", "sources must be a list"},
           {"{", "not valid JSON"}}) {
    const Status s = ParseRoomSceneJson(text, "scene.json").status();
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << text;
    EXPECT_NE(s.message().find("scene.json"), std::string::npos) << s.message();
    EXPECT_NE(s.message().find(expected), std::string::npos) << text << ": " << s.message();
  }
}

TEST(RoomSceneFiles, SimulateWritesTheRecordingTheMovedArrayAndEachSourcesDirection) {
  auto file = ParseRoomSceneJson(kScene, "scene.json");
  ASSERT_TRUE(file.ok());
  ArrayFile array;
  array.sound_speed_mps = 343.0;
  array.sensors_m = {{0.0405, 0, 0}, {0, 0.0405, 0}, {-0.0405, 0, 0}, {0, -0.0405, 0}};
  TempDir dir;
  auto files = SimulateRoomScene(*file, array, 1, std::nullopt, dir.File("out"));
  ASSERT_TRUE(files.ok()) << files.status().ToString();
  auto wav = ReadWav(files->wav_path);
  ASSERT_TRUE(wav.ok()) << wav.status().ToString();
  EXPECT_EQ(wav->channel_count, 4);
  EXPECT_EQ(wav->frames, 24000);
  auto moved = ReadArrayJson(files->array_path, ArrayUse::kAuto);
  ASSERT_TRUE(moved.ok()) << moved.status().ToString();
  EXPECT_TRUE(moved->sensors_m[0].isApprox(engine::Vec3(2.2405, 1.9, 1.0)));
  EXPECT_EQ(moved->sample_rate_hz, 16000.0);
  auto sources = CsvTable::Read(files->sources_path);
  ASSERT_TRUE(sources.ok()) << sources.status().ToString();
  ASSERT_EQ(sources->row_count(), 2u);
  const auto number = [&](size_t row, const std::string& name) {
    auto column = sources->Column(name);
    EXPECT_TRUE(column.ok()) << name;
    auto v = sources->Number(row, column.ok() ? *column : 0);
    return v.ok() ? *v : std::nan("");
  };
  // Source 0 from the board's centre (2.2, 1.9, 1.0): (1.8, 0.5, 0.4).
  const double azimuth = std::atan2(0.5, 1.8), range = std::sqrt(1.8 * 1.8 + 0.5 * 0.5 + 0.4 * 0.4);
  EXPECT_NEAR(number(0, "azimuth_rad"), azimuth, 1e-6);
  EXPECT_NEAR(number(0, "range_m"), range, 1e-6);
  auto sounding = CsvTable::Read(files->sounding_path);
  ASSERT_TRUE(sounding.ok());
  EXPECT_GE(sounding->row_count(), 2u);  // the broadband source throughout, the talker's bursts
  // A sensor outside the room is refused naming it.
  file->array_position_m = engine::Vec3(-1.0, 1.0, 1.0);
  EXPECT_NE(SimulateRoomScene(*file, array, 1, std::nullopt, dir.File("bad")).status().message().find("outside the room"),
            std::string::npos);
}

}  // namespace
}  // namespace localizer::io

namespace localizer::io {
namespace {

// The named scenes (scenes/): every room with every array renders (1 s of each, to keep it short).
TEST(RoomSceneFiles, EveryNamedSceneFitsEveryNamedArray) {
  const std::filesystem::path root = std::filesystem::path(LOCALIZER_SOURCE_DIR) / "scenes";
  int pairs = 0;
  for (const auto& room : std::filesystem::directory_iterator(root / "rooms")) {
    auto scene = ReadRoomSceneJson(room.path().string());
    ASSERT_TRUE(scene.ok()) << scene.status().ToString();
    for (const auto& array_path : std::filesystem::directory_iterator(root / "arrays")) {
      auto array = ReadArrayFile(array_path.path().string(), ArrayUse::kAuto);
      ASSERT_TRUE(array.ok()) << array.status().ToString();
      testing::TempDir dir;
      auto files = SimulateRoomScene(*scene, *array, 1, 1.0, dir.File("out"));
      EXPECT_TRUE(files.ok()) << room.path() << " with " << array_path.path() << ": " << files.status().ToString();
      ++pairs;
    }
  }
  EXPECT_EQ(pairs, 27);  // 9 rooms x 3 arrays: 1, 2 and 3 talkers, free, RT60 0.4 s and speech-like
}

}  // namespace
}  // namespace localizer::io
