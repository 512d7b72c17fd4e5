#include "engine/doa/array_shape.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

namespace localizer::engine {
namespace {

TEST(ArrayShape, ALineIsLinearWithItsDirectionAsAxis) {
  std::vector<Vec3> line;
  const Vec3 along = Vec3(1.0, 2.0, -0.5).normalized();
  for (int i = 0; i < 8; ++i) line.push_back(Vec3(0.3, -1.0, 2.0) + 0.04 * i * along);
  const StatusOr<ArrayShapeInfo> info = ClassifyArray(line);
  ASSERT_TRUE(info.ok()) << info.status().ToString();
  EXPECT_EQ(info->shape, ArrayShape::kLinear);
  EXPECT_NEAR(std::abs(info->axis.dot(along)), 1.0, 1e-12);
  EXPECT_NEAR(info->aperture_m, 0.28, 1e-12);
  EXPECT_STREQ(ArrayShapeName(info->shape), "linear");
}

TEST(ArrayShape, TwoSensorsAreALine) {
  const StatusOr<ArrayShapeInfo> info = ClassifyArray({Vec3::Zero(), Vec3(0.0, 0.0, 0.1)});
  ASSERT_TRUE(info.ok());
  EXPECT_EQ(info->shape, ArrayShape::kLinear);
  EXPECT_NEAR(info->axis.z(), 1.0, 1e-12);  // the sign is canonical: largest component positive
}

TEST(ArrayShape, ASquareAndACircleArePlanarWithTheirNormal) {
  const double a = 0.0405;
  const StatusOr<ArrayShapeInfo> square = ClassifyArray({Vec3(a, 0, 0), Vec3(0, a, 0), Vec3(-a, 0, 0), Vec3(0, -a, 0)});
  ASSERT_TRUE(square.ok());
  EXPECT_EQ(square->shape, ArrayShape::kPlanar);
  EXPECT_NEAR(square->axis.z(), 1.0, 1e-12);

  // A tilted 7-microphone circle (6 on the rim and one at the centre).
  const Vec3 normal = Vec3(0.2, -0.3, 1.0).normalized();
  const Vec3 e1 = normal.cross(Vec3::UnitX()).normalized(), e2 = normal.cross(e1);
  std::vector<Vec3> circle{Vec3(1.0, 2.0, 3.0)};
  for (int k = 0; k < 6; ++k)
    circle.push_back(circle[0] + 0.043 * (std::cos(k * M_PI / 3) * e1 + std::sin(k * M_PI / 3) * e2));
  const StatusOr<ArrayShapeInfo> info = ClassifyArray(circle);
  ASSERT_TRUE(info.ok());
  EXPECT_EQ(info->shape, ArrayShape::kPlanar);
  EXPECT_NEAR(std::abs(info->axis.dot(normal)), 1.0, 1e-12);
  EXPECT_TRUE((info->centroid_m - circle[0]).norm() < 1e-12);
}

TEST(ArrayShape, ATetrahedronIsVolumetric) {
  const StatusOr<ArrayShapeInfo> info = ClassifyArray({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)});
  ASSERT_TRUE(info.ok());
  EXPECT_EQ(info->shape, ArrayShape::kVolumetric);
  EXPECT_EQ(info->axis, Vec3::Zero());
}

TEST(ArrayShape, AHalfMillimetreOffThePlaneIsStillPlanar) {
  // 1 mm is the flatness floor: a board's tolerance does not make it a volume.
  const StatusOr<ArrayShapeInfo> info =
      ClassifyArray({Vec3(0.05, 0, 0), Vec3(0, 0.05, 0.0005), Vec3(-0.05, 0, 0), Vec3(0, -0.05, -0.0005)});
  ASSERT_TRUE(info.ok());
  EXPECT_EQ(info->shape, ArrayShape::kPlanar);
}

TEST(ArrayShape, BadArraysAreNamed) {
  EXPECT_EQ(ClassifyArray({Vec3::Zero()}).status().code(), StatusCode::kInvalidArgument);
  const Status coincident = ClassifyArray({Vec3::Zero(), Vec3(0.0005, 0, 0), Vec3(1, 0, 0)}).status();
  EXPECT_EQ(coincident.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(coincident.message().find("sensors 0 and 1"), std::string::npos) << coincident.message();
  const Status nan = ClassifyArray({Vec3::Zero(), Vec3(NAN, 0, 0)}).status();
  EXPECT_NE(nan.message().find("sensor 1"), std::string::npos) << nan.message();
}

// The mirror across a planar array's plane: the normal's side without a stated side, the
// stated side with one; a direction in the plane to the refinement's precision is its own
// mirror on every machine (the CPU's refinement left z = 1.5e-8 where the GPU's left 0).
TEST(ArrayShape, APlanarDirectionsMirrorIsAmbiguousOnlyWhenItIsAnotherDirection) {
  const Vec3 n(0, 0, 1);
  const Vec3 below = Vec3(0.6, 0.0, -0.8);
  const PlanarDirection free = ResolvePlanarMirror(below, n, Vec3::Zero());
  EXPECT_TRUE(free.direction.isApprox(Vec3(0.6, 0.0, 0.8)));
  EXPECT_TRUE(free.mirror_ambiguous);
  EXPECT_TRUE(free.mirror_direction.isApprox(below));
  const PlanarDirection stated = ResolvePlanarMirror(Vec3(0.6, 0.0, 0.8), n, Vec3(0, 0, -1));
  EXPECT_TRUE(stated.direction.isApprox(below));
  EXPECT_FALSE(stated.mirror_ambiguous);
  for (const double z : {0.0, 1.5e-8, -1.5e-8, 4e-6}) {
    const PlanarDirection in_plane = ResolvePlanarMirror(Vec3(std::sqrt(1 - z * z), 0.0, z), n, Vec3::Zero());
    EXPECT_FALSE(in_plane.mirror_ambiguous) << "z " << z;
    EXPECT_GE(in_plane.direction.z(), 0.0);
    EXPECT_TRUE(std::isnan(in_plane.mirror_direction.x()));
  }
  EXPECT_TRUE(ResolvePlanarMirror(Vec3(std::sqrt(1 - 1e-10), 0.0, 1e-5), n, Vec3::Zero()).mirror_ambiguous);
}
}  // namespace
}  // namespace localizer::engine
