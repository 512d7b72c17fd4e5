// Where a track's estimates go, one per frame as they come: a CSV (csv_io.h), JSON lines
// (estimates_jsonl.h) or GeoJSON points (estimates_geojson.h). `localizer-cli track --format
// csv|jsonl|geojson` picks one; all stream, so a long run writes as it goes and memory stays
// flat.
#pragma once

#include <fstream>
#include <memory>
#include <optional>
#include <string>

#include "clients/io/geodetic.h"
#include "engine/array/array_geometry.h"
#include "engine/core/estimate.h"
#include "engine/core/status.h"

namespace localizer::io {

enum class EstimatesFormat { kCsv, kJsonl, kGeoJson };
// "csv" | "jsonl" | "geojson"; INVALID_ARGUMENT naming the valid ones otherwise.
StatusOr<EstimatesFormat> ParseEstimatesFormat(const std::string& name);

class EstimatesWriter {
 public:
  virtual ~EstimatesWriter() = default;
  virtual Status Write(const engine::Estimate& estimate) = 0;
  // Flushes and closes; reports a failed write that the stream only notices at the end.
  virtual Status Close() = 0;
};

// What a format needs beyond the estimates: GeoJSON the array's geodetic origin with its
// heading (INVALID_ARGUMENT saying so otherwise); the others nothing.
Status CheckFormatNeeds(EstimatesFormat format, const std::optional<GeodeticOrigin>& origin);

// Closes `*out` (a no-op when null or already closed) and resets it; INVALID_ARGUMENT naming
// `path` when the stream failed, which a buffered stream may only notice now.
Status CloseOutput(std::unique_ptr<std::ofstream>* out, const std::string& path);

// The writer for a position session over `array` (CSV: one pair column group per
// non-reference sensor) or, with `array` null, a session that lists sources (CSV: one row
// per frame and source). `origin` as CheckFormatNeeds requires. A null writer when `path` is
// empty.
StatusOr<std::unique_ptr<EstimatesWriter>> OpenEstimatesWriter(const std::string& path, EstimatesFormat format,
                                                               const engine::ArrayGeometry* array,
                                                               const std::optional<GeodeticOrigin>& origin = {});

}  // namespace localizer::io
