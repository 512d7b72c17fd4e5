#include "clients/io/estimates_jsonl.h"

#include <cmath>
#include <utility>

#include <nlohmann/json.hpp>

#include "engine/core/track_status.h"

namespace localizer::io {
namespace {

using json = nlohmann::ordered_json;

// JSON has no NaN or infinity: those become null.
json Number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json Vector3(const engine::Vec3& v) { return json::array({Number(v.x()), Number(v.y()), Number(v.z())}); }

json Source(const engine::SourceEstimate& s) {
  json out = {{"source_id", s.source_id},
              {"status", engine::TrackStatusName(s.status)},
              {"source_present", s.source_present},
              {"azimuth_rad", Number(s.azimuth_rad)},
              {"elevation_rad", Number(s.elevation_rad)},
              {"cone_angle_rad", Number(s.cone_angle_rad)},
              {"sigma_rad", Number(s.sigma_rad)},
              {"power_db", Number(s.power_db)},
              {"range_sd_m", Number(s.range_sd_m)}};
  out["position_m"] = s.position_m.allFinite() ? Vector3(s.position_m) : json(nullptr);
  return out;
}

}  // namespace

std::string EstimateJsonLine(const engine::Estimate& e, const std::vector<int>& pair_sensors) {
  json line = {{"frame", e.frame_index},
               {"t_s", Number(e.t_s)},
               {"initialised", e.initialised},
               {"reinitialised", e.reinitialised},
               {"source_present", e.source_present},
               {"presence_statistic", Number(e.presence_statistic)},
               {"presence_threshold", Number(e.presence_threshold)},
               {"ambiguous", e.ambiguous},
               {"modes", e.modes},
               {"far_field", e.far_field},
               {"range_sd_m", Number(e.range_sd_m)},
               {"nis", Number(e.nis)},
               {"ess", Number(e.ess)},
               {"pairs_used", e.pairs_used},
               {"tdoa_sigma_s", Number(e.tdoa_sigma_s)},
               {"tdoa_ms", Number(e.timings.tdoa_s * 1e3)},
               {"filter_ms", Number(e.timings.filter_s * 1e3)}};
  if (e.initialised) {
    line["position_m"] = Vector3(e.state.head<3>());
    line["velocity_mps"] = Vector3(e.state.tail<3>());
    line["position_sd_m"] = Vector3(e.covariance.diagonal().head<3>().cwiseMax(0.0).cwiseSqrt());
    json rows = json::array();
    for (int r = 0; r < 6; ++r) {
      json row = json::array();
      for (int c = 0; c < 6; ++c) row.push_back(Number(e.covariance(r, c)));
      rows.push_back(std::move(row));
    }
    line["covariance"] = std::move(rows);
  }
  json pairs = json::array();
  for (size_t p = 0; p < pair_sensors.size(); ++p) {
    pairs.push_back({{"sensor", pair_sensors[p]},
                     {"delay_s", p < e.delay_s.size() ? Number(e.delay_s[p]) : json(nullptr)},
                     {"quality", p < e.quality.size() ? Number(e.quality[p]) : json(nullptr)}});
  }
  line["pairs"] = std::move(pairs);
  if (!e.model_probabilities.empty()) {
    json probabilities = json::object();
    for (const engine::ModelProbability& m : e.model_probabilities) probabilities[m.model] = Number(m.probability);
    line["model_probabilities"] = std::move(probabilities);
  }
  if (!e.sources.empty()) {
    json sources = json::array();
    for (const engine::SourceEstimate& s : e.sources) sources.push_back(Source(s));
    line["sources"] = std::move(sources);
  }
  return line.dump();
}

StatusOr<std::unique_ptr<EstimatesJsonlWriter>> EstimatesJsonlWriter::Open(const std::string& path,
                                                                           std::vector<int> pair_sensors) {
  std::unique_ptr<EstimatesJsonlWriter> writer(new EstimatesJsonlWriter());
  writer->path_ = path;
  writer->pair_sensors_ = std::move(pair_sensors);
  writer->out_ = std::make_unique<std::ofstream>(path);
  if (!*writer->out_) return InvalidArgument(path + ": cannot open for writing");
  return writer;
}

Status EstimatesJsonlWriter::Write(const engine::Estimate& estimate) {
  *out_ << EstimateJsonLine(estimate, pair_sensors_) << '\n';
  if (!*out_) return InvalidArgument(path_ + ": write failed");
  return Status::Ok();
}

Status EstimatesJsonlWriter::Close() { return CloseOutput(&out_, path_); }

}  // namespace localizer::io
