// track --format geojson (issue 19): the array frame placed on the Earth (geodetic.h) and
// estimates written as GeoJSON points.
#include "clients/io/estimates_geojson.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "clients/io/array_json.h"
#include "clients/io/geodetic.h"
#include "tests/clients/test_util.h"

namespace localizer::io {
namespace {

using nlohmann::json;
using testing::TempDir;

GeodeticOrigin Origin(double heading_deg) {
  GeodeticOrigin o;
  o.latitude_deg = 45.0;
  o.longitude_deg = -120.0;
  o.altitude_m = 10.0;
  o.heading_deg = heading_deg;
  return o;
}

// One degree of latitude at 45 N is 111.132 km (WGS84 meridian arc), one of longitude
// 78.847 km: a point 1 km north and 1 km east of the origin.
TEST(Geodetic, OffsetsFollowTheWgs84RadiiAndTheHeading) {
  const Geodetic north = ToGeodetic(Origin(0.0), engine::Vec3(0.0, 1000.0, 0.0));
  EXPECT_NEAR((north.latitude_deg - 45.0) * 111132.0, 1000.0, 0.5);
  EXPECT_DOUBLE_EQ(north.longitude_deg, -120.0);
  const Geodetic east = ToGeodetic(Origin(0.0), engine::Vec3(1000.0, 0.0, -3.0));
  EXPECT_NEAR((east.longitude_deg + 120.0) * 78847.0, 1000.0, 0.5);
  EXPECT_DOUBLE_EQ(east.altitude_m, 7.0);
  // Heading 90: +y points east, +x south.
  const Geodetic y_east = ToGeodetic(Origin(90.0), engine::Vec3(0.0, 1000.0, 0.0));
  EXPECT_NEAR((y_east.longitude_deg + 120.0) * 78847.0, 1000.0, 0.5);
  EXPECT_NEAR(y_east.latitude_deg, 45.0, 1e-9);
  const Geodetic x_south = ToGeodetic(Origin(90.0), engine::Vec3(1000.0, 0.0, 0.0));
  EXPECT_NEAR((x_south.latitude_deg - 45.0) * 111132.0, -1000.0, 0.5);
}

TEST(EstimatesGeoJson, PointsAtTheEstimatesAndAValidCollection) {
  TempDir dir;
  auto writer = EstimatesGeoJsonWriter::Open(dir.File("t.geojson"), Origin(0.0));
  ASSERT_TRUE(writer.ok()) << writer.status().ToString();
  engine::Estimate e;
  ASSERT_TRUE((*writer)->Write(e).ok());  // not initialised: no feature
  e.initialised = true;
  e.frame_index = 4;
  e.t_s = 0.5;
  e.state << 0.0, 1000.0, -2.0, 0, 0, 0;
  e.covariance = engine::Mat6::Identity() * 0.25;
  ASSERT_TRUE((*writer)->Write(e).ok());
  ASSERT_TRUE((*writer)->Close().ok());
  std::ifstream in(dir.File("t.geojson"));
  std::stringstream text;
  text << in.rdbuf();
  const json j = json::parse(text.str());
  EXPECT_EQ(j.at("type"), "FeatureCollection");
  ASSERT_EQ(j.at("features").size(), 1u);
  const json& f = j.at("features")[0];
  EXPECT_EQ(f.at("geometry").at("type"), "Point");
  const json& c = f.at("geometry").at("coordinates");  // RFC 7946: longitude, latitude, altitude
  EXPECT_DOUBLE_EQ(c[0].get<double>(), -120.0);
  EXPECT_NEAR((c[1].get<double>() - 45.0) * 111132.0, 1000.0, 0.5);
  EXPECT_DOUBLE_EQ(c[2].get<double>(), 8.0);
  EXPECT_EQ(f.at("properties").at("frame"), 4);
  EXPECT_DOUBLE_EQ(f.at("properties").at("position_sd_m")[0].get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(f.at("properties").at("y_m").get<double>(), 1000.0);
}

TEST(EstimatesGeoJson, NeedsTheHeadingAndAFormatName) {
  GeodeticOrigin no_heading = Origin(0.0);
  no_heading.heading_deg.reset();
  TempDir dir;
  const auto refused = EstimatesGeoJsonWriter::Open(dir.File("t.geojson"), no_heading);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find("heading_deg"), std::string::npos) << refused.status().message();
  EXPECT_EQ(*ParseEstimatesFormat("geojson"), EstimatesFormat::kGeoJson);
  EXPECT_FALSE(OpenEstimatesWriter(dir.File("u.geojson"), EstimatesFormat::kGeoJson, nullptr).ok())
      << "no origin at all";
}

TEST(ArrayJson, GeodeticOriginRoundTripsAndIsChecked) {
  const std::string base = R"({"sound_speed_mps": 1500, "sensors_m": [[0,0,0],[1,0,0],[0,1,0],[0,0,1]], )";
  auto array = ParseArrayJson(
      base + R"("geodetic_origin": {"latitude_deg": 49.48845, "longitude_deg": -124.655217, "heading_deg": 30}})", "a");
  ASSERT_TRUE(array.ok()) << array.status().ToString();
  ASSERT_TRUE(array->geodetic_origin);
  EXPECT_EQ(array->geodetic_origin->latitude_deg, 49.48845);
  EXPECT_EQ(array->geodetic_origin->altitude_m, 0.0);
  EXPECT_EQ(*array->geodetic_origin->heading_deg, 30.0);
  TempDir dir;
  ASSERT_TRUE(WriteArrayJson(dir.File("a.json"), *array).ok());
  auto again = ReadArrayJson(dir.File("a.json"));
  ASSERT_TRUE(again.ok()) << again.status().ToString();
  EXPECT_EQ(again->geodetic_origin->longitude_deg, -124.655217);
  EXPECT_EQ(*again->geodetic_origin->heading_deg, 30.0);
  for (const char* bad : {R"("geodetic_origin": {"latitude_deg": 91, "longitude_deg": 0}})",
                                 R"("geodetic_origin": {"latitude_deg": 10}})",
                                 R"("geodetic_origin": {"latitude_deg": 10, "longitude_deg": 0, "heading": 3}})"}) {
    auto refused = ParseArrayJson(base + bad, "a");
    ASSERT_FALSE(refused.ok()) << bad;
    EXPECT_NE(refused.status().message().find("geodetic_origin"), std::string::npos) << refused.status().message();
  }
}

}  // namespace
}  // namespace localizer::io
