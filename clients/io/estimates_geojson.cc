#include "clients/io/estimates_geojson.h"

#include <cmath>
#include <utility>

#include <nlohmann/json.hpp>

#include "engine/core/track_status.h"

namespace localizer::io {
namespace {

using json = nlohmann::ordered_json;

json Number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json PointFeature(const GeodeticOrigin& origin, const engine::Vec3& p_m, json properties) {
  const Geodetic g = ToGeodetic(origin, p_m);
  properties["x_m"] = Number(p_m.x());
  properties["y_m"] = Number(p_m.y());
  properties["z_m"] = Number(p_m.z());
  return {{"type", "Feature"},
          {"geometry", {{"type", "Point"}, {"coordinates", {g.longitude_deg, g.latitude_deg, g.altitude_m}}}},
          {"properties", std::move(properties)}};
}

}  // namespace

StatusOr<std::unique_ptr<EstimatesGeoJsonWriter>> EstimatesGeoJsonWriter::Open(const std::string& path,
                                                                               const GeodeticOrigin& origin) {
  LOCALIZER_RETURN_IF_ERROR(CheckFormatNeeds(EstimatesFormat::kGeoJson, origin));
  std::unique_ptr<EstimatesGeoJsonWriter> writer(new EstimatesGeoJsonWriter());
  writer->path_ = path;
  writer->origin_ = origin;
  writer->out_ = std::make_unique<std::ofstream>(path);
  if (!*writer->out_) return InvalidArgument(path + ": cannot open for writing");
  *writer->out_ << "{\"type\":\"FeatureCollection\",\"features\":[";
  return writer;
}

void EstimatesGeoJsonWriter::WriteFeature(const std::string& feature) {
  *out_ << (first_ ? "\n" : ",\n") << feature;
  first_ = false;
}

Status EstimatesGeoJsonWriter::Write(const engine::Estimate& e) {
  const json common = {{"frame", e.frame_index},
                       {"t_s", Number(e.t_s)},
                       {"source_present", e.source_present},
                       {"ambiguous", e.ambiguous},
                       {"far_field", e.far_field}};
  if (e.sources.empty() && e.initialised) {
    json properties = common;
    const engine::Vec3 sd = e.covariance.diagonal().head<3>().cwiseMax(0.0).cwiseSqrt();
    properties["position_sd_m"] = {Number(sd.x()), Number(sd.y()), Number(sd.z())};
    WriteFeature(PointFeature(origin_, e.state.head<3>(), std::move(properties)).dump());
  }
  for (const engine::SourceEstimate& s : e.sources) {
    if (!s.position_m.allFinite()) continue;
    json properties = common;
    properties["source_id"] = s.source_id;
    properties["status"] = engine::TrackStatusName(s.status);
    properties["source_present"] = s.source_present;
    WriteFeature(PointFeature(origin_, s.position_m, std::move(properties)).dump());
  }
  if (!*out_) return InvalidArgument(path_ + ": write failed");
  return Status::Ok();
}

Status EstimatesGeoJsonWriter::Close() {
  if (out_) *out_ << "\n]}\n";
  return CloseOutput(&out_, path_);
}

}  // namespace localizer::io
