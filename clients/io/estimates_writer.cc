#include "clients/io/estimates_writer.h"

#include <utility>
#include <vector>

#include "clients/io/csv_io.h"
#include "clients/io/estimates_geojson.h"
#include "clients/io/estimates_jsonl.h"

namespace localizer::io {

StatusOr<EstimatesFormat> ParseEstimatesFormat(const std::string& name) {
  if (name == "csv") return EstimatesFormat::kCsv;
  if (name == "jsonl") return EstimatesFormat::kJsonl;
  if (name == "geojson") return EstimatesFormat::kGeoJson;
  return InvalidArgument("format '" + name + "' is unknown; valid: csv, jsonl, geojson");
}

Status CheckFormatNeeds(EstimatesFormat format, const std::optional<GeodeticOrigin>& origin) {
  if (format == EstimatesFormat::kGeoJson && !(origin && origin->heading_deg)) {
    return InvalidArgument(
        "geojson needs the array's geodetic_origin with latitude_deg, longitude_deg and heading_deg (the bearing of "
        "the array frame's +y axis from true north)");
  }
  return Status::Ok();
}

Status CloseOutput(std::unique_ptr<std::ofstream>* out, const std::string& path) {
  if (!*out) return Status::Ok();
  (*out)->close();
  const bool failed = !**out;
  out->reset();
  if (failed) return InvalidArgument(path + ": write failed when closing");
  return Status::Ok();
}

StatusOr<std::unique_ptr<EstimatesWriter>> OpenEstimatesWriter(const std::string& path, EstimatesFormat format,
                                                               const engine::ArrayGeometry* array,
                                                               const std::optional<GeodeticOrigin>& origin) {
  LOCALIZER_RETURN_IF_ERROR(CheckFormatNeeds(format, origin));
  if (format == EstimatesFormat::kGeoJson) {
    if (path.empty()) return std::unique_ptr<EstimatesWriter>();
    auto writer = EstimatesGeoJsonWriter::Open(path, *origin);
    if (!writer.ok()) return writer.status();
    return std::unique_ptr<EstimatesWriter>(std::move(*writer));
  }
  if (path.empty()) return std::unique_ptr<EstimatesWriter>();
  std::vector<int> pair_sensors;
  for (int p = 0; array != nullptr && p < array->pair_count(); ++p) pair_sensors.push_back(array->sensor_of_pair(p));
  if (format == EstimatesFormat::kJsonl) {
    auto writer = EstimatesJsonlWriter::Open(path, std::move(pair_sensors));
    if (!writer.ok()) return writer.status();
    return std::unique_ptr<EstimatesWriter>(std::move(*writer));
  }
  auto writer = array != nullptr ? EstimatesCsvWriter::Open(path, pair_sensors) : EstimatesCsvWriter::OpenSources(path);
  if (!writer.ok()) return writer.status();
  return std::unique_ptr<EstimatesWriter>(std::make_unique<EstimatesCsvWriter>(std::move(*writer)));
}

}  // namespace localizer::io
