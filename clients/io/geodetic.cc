#include "clients/io/geodetic.h"

#include <cmath>
#include <numbers>

namespace localizer::io {

Geodetic ToGeodetic(const GeodeticOrigin& origin, const engine::Vec3& p_m) {
  constexpr double kA = 6378137.0;               // WGS84 semi-major axis, m
  constexpr double kE2 = 6.69437999014e-3;       // first eccentricity squared
  constexpr double kDeg = std::numbers::pi / 180.0;
  const double h = origin.heading_deg.value_or(0.0) * kDeg;
  const double east = p_m.x() * std::cos(h) + p_m.y() * std::sin(h);
  const double north = -p_m.x() * std::sin(h) + p_m.y() * std::cos(h);
  const double lat = origin.latitude_deg * kDeg;
  const double s2 = std::sin(lat) * std::sin(lat);
  const double w = std::sqrt(1.0 - kE2 * s2);
  const double meridian_m = kA * (1.0 - kE2) / (w * w * w);
  const double prime_vertical_m = kA / w;
  Geodetic g;
  g.latitude_deg = origin.latitude_deg + north / (meridian_m + origin.altitude_m) / kDeg;
  g.longitude_deg = origin.longitude_deg + east / ((prime_vertical_m + origin.altitude_m) * std::cos(lat)) / kDeg;
  g.altitude_m = origin.altitude_m + p_m.z();
  return g;
}

}  // namespace localizer::io
