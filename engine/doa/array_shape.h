// What an array's geometry can observe of a source: the shape of its sensor layout.
//
// The sensors' offsets from their centroid, as the rows of an N x 3 matrix, have singular
// values s1 >= s2 >= s3 (ArrayGeometry's test for 3-D localisation, same thresholds):
//   linear      s2 < 1e-3 s1 or s2 < 1 mm: every sensor on one line. Far-field delays
//               depend only on the cosine of the angle between the source direction and
//               the line (the cone angle); `axis` is the line's unit direction.
//   planar      not linear, s3 < 1e-3 s1 or s3 < 1 mm: every sensor in one plane. Delays
//               see only the in-plane part of the direction, so a direction and its mirror
//               image across the plane are indistinguishable; `axis` is the plane's unit
//               normal.
//   volumetric  otherwise: direction (far field) or 3-D position; `axis` is zero.
// The signs of `axis` are fixed so that its largest component is positive (deterministic).
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "engine/core/status.h"
#include "engine/core/types.h"

namespace localizer::engine {

enum class ArrayShape { kLinear, kPlanar, kVolumetric };

// "linear", "planar" or "volumetric".
const char* ArrayShapeName(ArrayShape shape);

struct ArrayShapeInfo {
  ArrayShape shape = ArrayShape::kVolumetric;
  Vec3 centroid_m = Vec3::Zero();
  Vec3 axis = Vec3::Zero();  // linear: along the line; planar: the normal; volumetric: zero
  double aperture_m = 0.0;   // largest distance between two sensors
};

// INVALID_ARGUMENT (naming the sensors) for fewer than 2 sensors, a non-finite coordinate,
// or two sensors closer than 1 mm.
StatusOr<ArrayShapeInfo> ClassifyArray(const std::vector<Vec3>& sensors_m);

// A planar array's refined direction u against its mirror image across the plane (normal n):
// with a stated side (non-zero `side`), the one on that side; without, the one on the
// normal's side, and mirror_ambiguous when the mirror is another direction: more than
// kMirrorDistinctRad from u. A direction in the plane to the refinement's precision (its
// steps stop at 1e-5 rad) is its own mirror: its out-of-plane part (1e-8 on one machine, 0 on
// another) is rounding, and a flag decided by it would differ between the CPU and the GPU.
constexpr double kMirrorDistinctRad = 1e-5;
struct PlanarDirection {
  Vec3 direction;
  bool mirror_ambiguous = false;
  Vec3 mirror_direction;  // NaN when not ambiguous
};
PlanarDirection ResolvePlanarMirror(const Vec3& u, const Vec3& normal, const Vec3& side);

// The angles of a unit direction u in the array's frame: azimuth = atan2(y, x), elevation
// from the x-y plane towards +z, and the cone angle to a linear array's axis, in [0, pi].
inline double AzimuthRad(const Vec3& u) { return std::atan2(u.y(), u.x()); }
inline double ElevationRad(const Vec3& u) { return std::asin(std::clamp(u.z(), -1.0, 1.0)); }
inline double ConeAngleRad(const Vec3& u, const Vec3& axis) { return std::acos(std::clamp(u.dot(axis), -1.0, 1.0)); }

}  // namespace localizer::engine
