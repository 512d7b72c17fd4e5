// Where the array is on the Earth, for results in latitude and longitude (GeoJSON output).
//
// The array frame is local: x, y, z in metres about some origin, z up. A GeodeticOrigin puts
// that origin at a WGS84 latitude, longitude and altitude, and heading_deg turns it: the
// compass bearing of the array frame's +y axis, clockwise from true north (0: +y north and
// +x east; 90: +y east and +x south). A point (x, y, z) lies at
//     east  = x cos h + y sin h,   north = -x sin h + y cos h,   up = z
// from the origin, and at
//     latitude  = lat0 + north / (M + alt0),   longitude = lon0 + east / ((N + alt0) cos lat0)
// with M and N the WGS84 meridian and prime-vertical radii of curvature at lat0. This is the
// local tangent plane: for offsets under 1 km its error is under 0.1 m, far below what an
// acoustic array resolves at that range; it is not meant for tracks kilometres long.
#pragma once

#include <optional>

#include "engine/core/types.h"

namespace localizer::io {

struct GeodeticOrigin {
  double latitude_deg = 0.0;   // [-90, 90], WGS84
  double longitude_deg = 0.0;  // [-180, 180]
  double altitude_m = 0.0;     // above the ellipsoid
  // The array frame's +y axis, degrees clockwise from true north; unset when unknown (a
  // deployment sheet that gives the position but not the orientation).
  std::optional<double> heading_deg;
};

struct Geodetic {
  double latitude_deg = 0.0, longitude_deg = 0.0, altitude_m = 0.0;
};

// The point `p_m` of the array frame. Needs origin.heading_deg.
Geodetic ToGeodetic(const GeodeticOrigin& origin, const engine::Vec3& p_m);

}  // namespace localizer::io
