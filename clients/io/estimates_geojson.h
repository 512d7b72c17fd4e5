// Estimates as GeoJSON (RFC 7946): one FeatureCollection whose Features are Points at the
// estimated positions, in WGS84 longitude, latitude and altitude (geodetic.h places the
// array), written as the run goes (`localizer-cli track --format geojson`).
//
// A frame with a position (initialised) gives one Feature, properties
//   {"frame", "t_s", "source_present", "ambiguous", "far_field", "position_sd_m" [sx, sy, sz],
//    "x_m", "y_m", "z_m" (the array frame)};
// a session that lists sources gives one Feature per source whose position the frame bounds,
// with "source_id" and "status" added. Frames without a position give none. Non-finite
// numbers are null (RFC 7946 JSON has no NaN). The file is valid GeoJSON only once Close()
// wrote the closing brackets; a run cut short leaves it open.
#pragma once

#include <fstream>
#include <memory>
#include <string>

#include "clients/io/estimates_writer.h"
#include "clients/io/geodetic.h"

namespace localizer::io {

class EstimatesGeoJsonWriter final : public EstimatesWriter {
 public:
  // INVALID_ARGUMENT unless origin.heading_deg is set (the frame's axes must be placed).
  static StatusOr<std::unique_ptr<EstimatesGeoJsonWriter>> Open(const std::string& path, const GeodeticOrigin& origin);
  Status Write(const engine::Estimate& estimate) override;
  Status Close() override;

 private:
  EstimatesGeoJsonWriter() = default;
  void WriteFeature(const std::string& feature);
  std::string path_;
  GeodeticOrigin origin_;
  std::unique_ptr<std::ofstream> out_;
  bool first_ = true;
};

}  // namespace localizer::io
