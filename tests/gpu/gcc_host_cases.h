// What the host tests of the GPU GCC maths share (gcc_math_test.cu, gcc_emulation_test.cu):
// the interpolations and weightings they sweep, a relative difference, and a tetrahedron of a
// chosen size.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "engine/array/array_geometry.h"
#include "engine/tdoa/gcc_phat.h"
#include "tests/tdoa/tdoa_test_signals.h"

namespace localizer::gpu::testing {

using engine::PeakInterpolation;
using engine::Weighting;

inline constexpr PeakInterpolation kMethods[] = {PeakInterpolation::kParabolic, PeakInterpolation::kGaussian,
                                                 PeakInterpolation::kSinc};
inline constexpr Weighting kWeightings[] = {Weighting::kPhat, Weighting::kPhatBeta, Weighting::kScot, Weighting::kCc};

inline double RelativeDifference(double a, double b) {
  return std::abs(a - b) / std::max({std::abs(a), std::abs(b), 1e-30});
}

inline engine::ArrayGeometry ScaledTetrahedron(double scale, double sound_speed_mps) {
  std::vector<engine::Vec3> sensors = engine::testing::TetrahedronSensors();
  for (auto& s : sensors) s *= scale;
  return *engine::ArrayGeometry::Create(sensors, sound_speed_mps);
}

}  // namespace localizer::gpu::testing
