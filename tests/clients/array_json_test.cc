#include "clients/io/array_json.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "clients/io/xav_array.h"
#include "tests/clients/test_util.h"

namespace localizer::io {
namespace {

using testing::TempDir;

constexpr const char* kTetra = R"({
  "sound_speed_mps": 1500.0,
  "sample_rate_hz": 11025,
  "sensors_m": [[0, 0, 0], [2, 0, 0], [0, 2, 0], [0, 0, 2]],
  "reference_sensor": 1
})";

std::string ErrorOf(const std::string& text) {
  auto array = ParseArrayJson(text, "test.json");
  return array.ok() ? "" : array.status().message();
}

TEST(ArrayJson, ParsesEveryField) {
  auto array = ParseArrayJson(kTetra, "test.json");
  ASSERT_TRUE(array.ok()) << array.status().ToString();
  EXPECT_EQ(array->sound_speed_mps, 1500.0);
  ASSERT_TRUE(array->sample_rate_hz.has_value());
  EXPECT_EQ(*array->sample_rate_hz, 11025.0);
  ASSERT_EQ(array->sensors_m.size(), 4u);
  EXPECT_EQ(array->sensors_m[3], engine::Vec3(0, 0, 2));
  EXPECT_EQ(array->reference_sensor, 1);
}

TEST(ArrayJson, OptionalFieldsDefault) {
  auto array = ParseArrayJson(R"({"sound_speed_mps": 343, "sensors_m": [[0,0,0],[1,0,0],[0,1,0],[0,0,1]]})", "t");
  ASSERT_TRUE(array.ok()) << array.status().ToString();
  EXPECT_FALSE(array->sample_rate_hz.has_value());
  EXPECT_EQ(array->reference_sensor, 0);
}

TEST(ArrayJson, WriteThenReadRoundTrips) {
  TempDir dir;
  ArrayFile written;
  written.sound_speed_mps = 1484.0;
  written.sample_rate_hz = 32000.0;
  written.reference_sensor = 2;
  written.sensors_m = {{0.1, -0.2, 0.3}, {1.0 / 3.0, 0, 0}, {0, 1.7, 0}, {0, 0, 1.1}};
  written.band_hz = std::make_pair(50.0, 1000.0);
  ASSERT_TRUE(WriteArrayJson(dir.File("array.json"), written).ok());
  auto read = ReadArrayJson(dir.File("array.json"));
  ASSERT_TRUE(read.ok()) << read.status().ToString();
  EXPECT_EQ(read->sound_speed_mps, written.sound_speed_mps);
  EXPECT_EQ(read->sample_rate_hz, written.sample_rate_hz);
  EXPECT_EQ(read->reference_sensor, 2);
  EXPECT_EQ(read->sensors_m, written.sensors_m);  // doubles survive the text exactly
  EXPECT_EQ(read->band_hz, written.band_hz);
}

TEST(ArrayJson, BandHintMustBeAnOrderedPair) {
  const std::string head = R"({"sound_speed_mps": 343, "sensors_m": [[0,0,0],[1,0,0],[0,1,0],[0,0,1]], "band_hz": )";
  EXPECT_NE(ErrorOf(head + "[3000, 300]}").find("band_hz"), std::string::npos);
  EXPECT_NE(ErrorOf(head + "[300]}").find("band_hz"), std::string::npos);
  EXPECT_EQ(ErrorOf(head + "[300, 3000]}"), "");
}

TEST(ArrayJson, ErrorsNameTheField) {
  const std::string sensors = R"("sensors_m": [[0,0,0],[1,0,0],[0,1,0],[0,0,1]])";
  EXPECT_NE(ErrorOf(R"({"sound_speed_mps": 1500})").find("missing required field sensors_m"), std::string::npos);
  EXPECT_NE(ErrorOf("{" + sensors + "}").find("missing required field sound_speed_mps"), std::string::npos);
  EXPECT_NE(ErrorOf(R"({"sound_speed_mps": "fast", )" + sensors + "}").find("sound_speed_mps"), std::string::npos);
  EXPECT_NE(ErrorOf(R"({"sound_speed_mps": -1, )" + sensors + "}").find("must be > 0"), std::string::npos);
  const std::string bad_coordinate =
      ErrorOf(R"({"sound_speed_mps": 1500, "sensors_m": [[0,0,0],[1,"x",0],[0,1,0],[0,0,1]]})");
  EXPECT_NE(bad_coordinate.find("sensors_m[1][1]"), std::string::npos) << bad_coordinate;
  EXPECT_NE(bad_coordinate.find("not a number"), std::string::npos) << bad_coordinate;
  EXPECT_NE(ErrorOf(R"({"sound_speed_mps": 1500, "sensors_m": [[0,0,0],[1,0]]})").find("sensors_m[1]"),
            std::string::npos);
  EXPECT_NE(ErrorOf(R"({"sound_speed_mps": 1e999, )" + sensors + "}").find("not valid JSON"), std::string::npos);
  EXPECT_NE(ErrorOf(R"({"sound_speed_mps": 1500, "reference_sensr": 1, )" + sensors + "}")
                .find("unknown field \"reference_sensr\""),
            std::string::npos);
  EXPECT_NE(ErrorOf(R"({"sound_speed_mps": 1500, "reference_sensor": 1.5, )" + sensors + "}").find("reference_sensor"),
            std::string::npos);
  EXPECT_NE(ErrorOf("[1, 2]").find("JSON object"), std::string::npos);
  EXPECT_NE(ErrorOf("{not json").find("not valid JSON"), std::string::npos);
}

// Found with fuzz_array_json's invariant (the index kept is the integer written): an index
// beyond int was truncated, so 4294967297 was read as sensor 1 and accepted.
TEST(ArrayJson, ReferenceSensorBeyondIntIsRefusedNotTruncated) {
  const std::string head = R"({"sound_speed_mps": 1500, "sensors_m": [[0,0,0],[1,0,0],[0,1,0],[0,0,1]], )";
  for (const char* reference : {"4294967297", "4294967296", "18446744073709551615", "-4294967295", "2147483648"}) {
    const std::string error = ErrorOf(head + "\"reference_sensor\": " + reference + "}");
    EXPECT_NE(error.find("reference_sensor is " + std::string(reference)), std::string::npos)
        << reference << ": " << error;
  }
  EXPECT_EQ(ErrorOf(head + R"("reference_sensor": 3})"), "");
}

TEST(ArrayJson, BoundsAndWaterColumn) {
  const std::string head = R"({"sound_speed_mps": 1500, "sensors_m": [[0,0,0],[1,0,0],[0,1,0],[0,0,1]], )";
  constexpr double kInf = std::numeric_limits<double>::infinity();
  auto unbounded = ParseArrayJson(head + R"("reference_sensor": 0})", "t");
  ASSERT_TRUE(unbounded.ok());
  EXPECT_FALSE(unbounded->has_bounds());
  EXPECT_EQ(unbounded->bounds_min_m, engine::Vec3::Constant(-kInf));
  EXPECT_EQ(unbounded->bounds_max_m, engine::Vec3::Constant(kInf));

  auto water = ParseArrayJson(head + R"("surface_z_m": 7.03, "bottom_z_m": -0.97})", "t");
  ASSERT_TRUE(water.ok()) << water.status().ToString();
  EXPECT_EQ(water->bounds_max_m, engine::Vec3(kInf, kInf, 7.03));
  EXPECT_EQ(water->bounds_min_m, engine::Vec3(-kInf, -kInf, -0.97));

  auto box = ParseArrayJson(head + R"("bounds_min_m": [-10, null, "-inf"], "bounds_max_m": [10, 20, null]})", "t");
  ASSERT_TRUE(box.ok()) << box.status().ToString();
  EXPECT_EQ(box->bounds_min_m, engine::Vec3(-10, -kInf, -kInf));
  EXPECT_EQ(box->bounds_max_m, engine::Vec3(10, 20, kInf));

  // Written and read back: open sides as null.
  TempDir dir;
  ArrayFile written = *box;
  written.bounds_min_m.z() = -0.97;
  ASSERT_TRUE(WriteArrayJson(dir.File("array.json"), written).ok());
  auto read = ReadArrayJson(dir.File("array.json"));
  ASSERT_TRUE(read.ok()) << read.status().ToString();
  EXPECT_EQ(read->bounds_min_m, written.bounds_min_m);
  EXPECT_EQ(read->bounds_max_m, written.bounds_max_m);

  // Errors name the field.
  EXPECT_NE(ErrorOf(head + R"("surface_z_m": -5, "bottom_z_m": 3})").find("bottom_z_m below surface_z_m"),
            std::string::npos);
  EXPECT_NE(ErrorOf(head + R"("bounds_min_m": ["inf", 0, 0]})").find("bounds_min_m[0]"), std::string::npos);
  EXPECT_NE(ErrorOf(head + R"("bounds_max_m": [1, 2]})").find("bounds_max_m"), std::string::npos);
  EXPECT_NE(ErrorOf(head + R"("bounds_max_m": [null, null, 1], "surface_z_m": 2})").find("surface_z_m"),
            std::string::npos);
  EXPECT_NE(ErrorOf(head + R"("bottom_z_m": "deep"})").find("bottom_z_m"), std::string::npos);
}

TEST(ArrayJson, GeometryErrorsFlowThroughFromTheEngine) {
  const std::string three = ErrorOf(R"({"sound_speed_mps": 1500, "sensors_m": [[0,0,0],[1,0,0],[0,1,0]]})");
  EXPECT_NE(three.find("test.json"), std::string::npos) << three;
  EXPECT_NE(three.find("at least 4"), std::string::npos) << three;
  const std::string reference = ErrorOf(
      R"({"sound_speed_mps": 1500, "reference_sensor": 4,
          "sensors_m": [[0,0,0],[1,0,0],[0,1,0],[0,0,1]]})");
  EXPECT_FALSE(reference.empty());
}

TEST(ArrayJson, MissingFileIsNotFound) {
  auto array = ReadArrayJson("/nonexistent/array.json");
  ASSERT_FALSE(array.ok());
  EXPECT_EQ(array.status().code(), StatusCode::kNotFound);
}

TEST(ArrayJson, ReadArrayFileTakesTheXavCsv) {
  auto array = ReadArrayFile(testing::XavConfigCsv());
  ASSERT_TRUE(array.ok()) << array.status().ToString();
  ASSERT_EQ(array->sensors_m.size(), 6u);
  EXPECT_EQ(array->sound_speed_mps, 1484.0);  // localization_config_large_array.yaml
  EXPECT_EQ(array->reference_sensor, 3);
  EXPECT_EQ(array->sensors_m[5], engine::Vec3(0.858, 0.86, 0.671));
  // The water column (8 m deep, z up, the surface 7.03 m above the array frame's origin).
  EXPECT_NEAR(array->bounds_max_m.z(), 7.03, 0.005);
  EXPECT_DOUBLE_EQ(array->bounds_min_m.z(), array->bounds_max_m.z() - 8.0);
  EXPECT_FALSE(std::isfinite(array->bounds_min_m.x()));
  EXPECT_FALSE(std::isfinite(array->bounds_max_m.y()));
}

}  // namespace
}  // namespace localizer::io

namespace localizer::io {
namespace {

TEST(ArrayJson, DirectionFieldsAreReadWrittenAndCheckedAgainstTheUse) {
  const std::string board = R"({"sound_speed_mps": 343, "sensors_m": [[0.04,0,0],[0,0.04,0],[-0.04,0,0],[0,-0.04,0]],
      "localization": "direction", "source_side": {"normal": [0, 0, 2]}, "max_sources": 3})";
  auto array = ParseArrayJson(board, "board.json", ArrayUse::kDirection);
  ASSERT_TRUE(array.ok()) << array.status().ToString();
  EXPECT_EQ(array->localization, ArrayFile::Localization::kDirection);
  ASSERT_TRUE(array->source_side_normal.has_value());
  EXPECT_EQ(*array->source_side_normal, engine::Vec3(0, 0, 2));
  EXPECT_EQ(array->max_sources, 3);
  // A file that says "direction" is not for positions, and one that says "position" not for doa.
  const Status for_positions = ParseArrayJson(board, "board.json").status();
  EXPECT_NE(for_positions.message().find("localization is \"direction\""), std::string::npos)
      << for_positions.message();
  const std::string tetra_position =
      R"({"sound_speed_mps": 343, "sensors_m": [[0,0,0],[1,0,0],[0,1,0],[0,0,1]], "localization": "position"})";
  EXPECT_TRUE(ParseArrayJson(tetra_position, "t").ok());
  EXPECT_EQ(ParseArrayJson(tetra_position, "t", ArrayUse::kDirection).status().code(), StatusCode::kInvalidArgument);

  TempDir dir;
  ASSERT_TRUE(WriteArrayJson(dir.File("a.json"), *array).ok());
  auto again = ReadArrayJson(dir.File("a.json"), ArrayUse::kDirection);
  ASSERT_TRUE(again.ok()) << again.status().ToString();
  EXPECT_EQ(again->localization, array->localization);
  EXPECT_EQ(again->source_side_normal, array->source_side_normal);
  EXPECT_EQ(again->max_sources, array->max_sources);
}

TEST(ArrayJson, SourcePlaneIsReadWrittenAndALineWithItIsAccepted) {
  const std::string line = R"({"sound_speed_mps": 343, "sensors_m": [[0,0,1.5],[0.1,0,1.5],[0.2,0,1.5]],
      "localization": "position", "source_plane": {"point_m": [0, 0, 1.5], "normal": [0, 0, 1]},
      "source_side": {"normal": [0, 1, 0]}})";
  auto array = ParseArrayJson(line, "line.json", ArrayUse::kAuto);
  ASSERT_TRUE(array.ok()) << array.status().ToString();
  ASSERT_TRUE(array->source_plane.has_value());
  EXPECT_EQ(array->source_plane->point_m, engine::Vec3(0, 0, 1.5));
  EXPECT_EQ(array->source_plane->normal, engine::Vec3::UnitZ());
  TempDir dir;
  ASSERT_TRUE(WriteArrayJson(dir.File("l.json"), *array).ok());
  auto again = ReadArrayJson(dir.File("l.json"), ArrayUse::kAuto);
  ASSERT_TRUE(again.ok()) << again.status().ToString();
  ASSERT_TRUE(again->source_plane.has_value());
  EXPECT_EQ(again->source_plane->normal, array->source_plane->normal);
  const std::string head = R"({"sound_speed_mps": 343, "sensors_m": [[0,0,0],[1,0,0],[2,0,0]], )";
  for (const auto& [field, expected] : std::vector<std::pair<std::string, std::string>>{
           {R"("source_plane": {"normal": [0, 0, 1]}})", "source_plane must be"},
           {R"("source_plane": {"point_m": [0, 0], "normal": [0, 0, 1]}})", "source_plane.point_m"},
           {R"("source_plane": {"point_m": [0, 0, 0], "normal": [0, 0, 0]}})", "must not be zero"}}) {
    const Status s = ParseArrayJson(head + field, "l.json", ArrayUse::kAuto).status();
    EXPECT_NE(s.message().find(expected), std::string::npos) << field << ": " << s.message();
  }
}

TEST(ArrayJson, BadDirectionFieldsAreNamed) {
  const std::string head = R"({"sound_speed_mps": 343, "sensors_m": [[0,0,0],[1,0,0],[0,1,0],[0,0,1]], )";
  for (const auto& [field, expected] : std::vector<std::pair<std::string, std::string>>{
           {R"("localization": "sideways"})", "localization must be"},
           {R"("source_side": [0, 0, 1]})", "source_side must be"},
           {R"("source_side": {"normal": [0, 0, 0]}})", "must not be zero"},
           {R"("source_side": {"normal": [0, "a", 1]}})", "source_side.normal"},
           {R"("max_sources": 17})", "max_sources must be"},
           {R"("max_sources": 2.5})", "max_sources must be"}}) {
    const Status s = ParseArrayJson(head + field, "t.json", ArrayUse::kDirection).status();
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << field;
    EXPECT_NE(s.message().find(expected), std::string::npos) << field << ": " << s.message();
  }
}

}  // namespace
}  // namespace localizer::io
