// Synthetic SRP peaks for DirectionTracker tests: a planar board (normal +z), the frame period
// of 256-sample hops at 16 kHz, and peaks at a given azimuth, statistic and rise.
#pragma once

#include "engine/doa/array_shape.h"
#include "engine/doa/srp_phat.h"
#include "tests/doa/plane_wave.h"

namespace localizer::engine::testing {

inline constexpr double kHop_s = 256.0 / 16000.0;

inline ArrayShapeInfo Board() {
  ArrayShapeInfo shape;
  shape.shape = ArrayShape::kPlanar;
  shape.axis = Vec3::UnitZ();
  return shape;
}

// A peak against a threshold of 4.3 with the given rise (past the threshold: an onset).
inline DirectionPeak PeakAt(double azimuth_rad, double elevation_rad, double statistic, double rise) {
  DirectionPeak peak;
  peak.direction = FromAzimuthElevation(azimuth_rad, elevation_rad);
  peak.azimuth_rad = azimuth_rad;
  peak.elevation_rad = elevation_rad;
  peak.statistic = statistic;
  peak.threshold = 4.3;
  peak.rise = rise;
  return peak;
}

// A talker's peak at elevation 0.3 rad, statistic 20.
inline DirectionPeak TalkerPeak(double azimuth_rad, double rise) { return PeakAt(azimuth_rad, 0.3, 20.0, rise); }

}  // namespace localizer::engine::testing
