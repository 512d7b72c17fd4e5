#include "engine/doa/array_shape.h"

#include <Eigen/SVD>
#include <limits>
#include <string>
#include <utility>

namespace localizer::engine {
namespace {
constexpr double kRelativeFlatness = 1e-3;  // as ArrayGeometry
constexpr double kFlatness_m = 1e-3;
constexpr double kCoincident_m = 1e-3;

Vec3 Canonical(Vec3 v) {
  Eigen::Index largest = 0;
  v.cwiseAbs().maxCoeff(&largest);
  return v(largest) < 0.0 ? Vec3(-v) : v;
}
}  // namespace

const char* ArrayShapeName(ArrayShape shape) {
  switch (shape) {
    case ArrayShape::kLinear:
      return "linear";
    case ArrayShape::kPlanar:
      return "planar";
    case ArrayShape::kVolumetric:
      return "volumetric";
  }
  return "volumetric";
}

StatusOr<ArrayShapeInfo> ClassifyArray(const std::vector<Vec3>& sensors_m) {
  const size_t n = sensors_m.size();
  if (n < 2) return InvalidArgument("an array needs at least 2 sensors, got " + std::to_string(n));
  ArrayShapeInfo info;
  for (size_t i = 0; i < n; ++i) {
    if (!sensors_m[i].allFinite())
      return InvalidArgument("sensor " + std::to_string(i) + " has a non-finite coordinate");
    info.centroid_m += sensors_m[i] / static_cast<double>(n);
  }
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = i + 1; j < n; ++j) {
      const double distance_m = (sensors_m[i] - sensors_m[j]).norm();
      if (distance_m < kCoincident_m) {
        return InvalidArgument("sensors " + std::to_string(i) + " and " + std::to_string(j) + " are closer than 1 mm");
      }
      info.aperture_m = std::max(info.aperture_m, distance_m);
    }
  }
  Eigen::MatrixXd centred(static_cast<Eigen::Index>(n), 3);
  for (size_t i = 0; i < n; ++i)
    centred.row(static_cast<Eigen::Index>(i)) = (sensors_m[i] - info.centroid_m).transpose();
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(centred, Eigen::ComputeFullV);
  // Two sensors give a 2 x 3 matrix and only 2 singular values: the missing ones are 0.
  Eigen::Vector3d sv = Eigen::Vector3d::Zero();
  for (Eigen::Index k = 0; k < svd.singularValues().size() && k < 3; ++k) sv(k) = svd.singularValues()(k);
  auto flat = [&](double s) { return s < kRelativeFlatness * sv(0) || s < kFlatness_m; };
  if (flat(sv(1))) {
    info.shape = ArrayShape::kLinear;
    info.axis = Canonical(svd.matrixV().col(0));
  } else if (flat(sv(2))) {
    info.shape = ArrayShape::kPlanar;
    info.axis = Canonical(svd.matrixV().col(2));
  } else {
    info.shape = ArrayShape::kVolumetric;
  }
  return info;
}

PlanarDirection ResolvePlanarMirror(const Vec3& u, const Vec3& normal, const Vec3& side) {
  PlanarDirection out;
  out.direction = u;
  Vec3 mirror = u - 2.0 * u.dot(normal) * normal;
  out.mirror_direction = Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
  if (side.norm() > 0.0) {
    if (u.dot(side) < mirror.dot(side)) out.direction = mirror;
    return out;
  }
  if (u.dot(normal) < 0.0) std::swap(out.direction, mirror);
  // The chord between unit vectors is their angle to first order.
  out.mirror_ambiguous = (out.direction - mirror).norm() > kMirrorDistinctRad;
  if (out.mirror_ambiguous) out.mirror_direction = mirror;
  return out;
}

}  // namespace localizer::engine
