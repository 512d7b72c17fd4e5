#include "gpu/srp/srp_grid.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace localizer::gpu {

std::vector<engine::Vec3> FibonacciDirections(int count) {
  std::vector<engine::Vec3> out;
  out.reserve(static_cast<size_t>(std::max(count, 0)));
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < count; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / count;
    const double rho = std::sqrt(std::max(0.0, 1.0 - z * z));
    out.emplace_back(rho * std::cos(golden * i), rho * std::sin(golden * i), z);
  }
  return out;
}

std::vector<engine::Vec3> CpuLikeGrid(const SrpArrayModel& array) {
  // The CPU's constants (srp_phat.cc): kMinRoots 16, kMaxRoots 8192, kRootCoverage 1.5.
  constexpr int kMinRoots = 16, kMaxRoots = 8192;
  constexpr double kRootCoverage = 1.5;
  const double leaf_radius = 0.5 / array.max_spread;
  std::vector<engine::Vec3> out;
  if (array.shape.shape == engine::ArrayShape::kLinear) {
    const int count = std::clamp(static_cast<int>(std::ceil(std::numbers::pi / (2.0 * leaf_radius))), kMinRoots, kMaxRoots);
    const double radius = 0.5 * std::numbers::pi / count;
    const engine::Vec3& axis = array.shape.axis;
    const engine::Vec3 other = std::abs(axis.x()) < 0.9 ? engine::Vec3::UnitX() : engine::Vec3::UnitY();
    const engine::Vec3 across = axis.cross(other).normalized();
    for (int i = 0; i < count; ++i) {
      const double theta = (2 * i + 1) * radius;
      out.push_back(std::cos(theta) * axis + std::sin(theta) * across);
    }
    return out;
  }
  const double needed = std::pow(kRootCoverage * 2.0 / leaf_radius, 2.0);
  const int count =
      static_cast<int>(std::clamp(std::ceil(needed), 8.0 * kMinRoots, static_cast<double>(kMaxRoots)));
  const double radius = kRootCoverage * 2.0 / std::sqrt(static_cast<double>(count));
  for (const engine::Vec3& u : FibonacciDirections(count)) {
    if (array.shape.shape == engine::ArrayShape::kPlanar && u.dot(array.shape.axis) < -std::sin(radius)) continue;
    out.push_back(u);
  }
  return out;
}

}  // namespace localizer::gpu
