#include "clients/python/engine_module/estimate_arrays.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include "clients/python/engine_module/numpy_convert.h"

namespace localizer::python {

namespace {

// The scalar double columns of a frame row, with the value each takes from an Estimate.
struct DoubleColumn {
  const char* name;
  double (*get)(const engine::Estimate&);
};
const DoubleColumn kDoubleColumns[] = {
    {"t_s", [](const engine::Estimate& e) { return e.t_s; }},
    {"x_m", [](const engine::Estimate& e) { return e.state[0]; }},
    {"y_m", [](const engine::Estimate& e) { return e.state[1]; }},
    {"z_m", [](const engine::Estimate& e) { return e.state[2]; }},
    {"vx_mps", [](const engine::Estimate& e) { return e.state[3]; }},
    {"vy_mps", [](const engine::Estimate& e) { return e.state[4]; }},
    {"vz_mps", [](const engine::Estimate& e) { return e.state[5]; }},
    // Position standard deviations: the covariance's diagonal, as estimates.csv's sx_m..sz_m.
    {"sx_m", [](const engine::Estimate& e) { return std::sqrt(std::max(0.0, e.covariance(0, 0))); }},
    {"sy_m", [](const engine::Estimate& e) { return std::sqrt(std::max(0.0, e.covariance(1, 1))); }},
    {"sz_m", [](const engine::Estimate& e) { return std::sqrt(std::max(0.0, e.covariance(2, 2))); }},
    {"presence_statistic", [](const engine::Estimate& e) { return e.presence_statistic; }},
    {"presence_threshold", [](const engine::Estimate& e) { return e.presence_threshold; }},
    {"range_sd_m", [](const engine::Estimate& e) { return e.range_sd_m; }},
    {"ess", [](const engine::Estimate& e) { return e.ess; }},
    {"nis", [](const engine::Estimate& e) { return e.nis; }},
    {"tdoa_sigma_s", [](const engine::Estimate& e) { return e.tdoa_sigma_s; }},
    {"tdoa_wall_s", [](const engine::Estimate& e) { return e.timings.tdoa_s; }},
    {"filter_wall_s", [](const engine::Estimate& e) { return e.timings.filter_s; }},
};

struct BoolColumn {
  const char* name;
  bool (*get)(const engine::Estimate&);
};
const BoolColumn kBoolColumns[] = {
    {"initialised", [](const engine::Estimate& e) { return e.initialised; }},
    {"reinitialised", [](const engine::Estimate& e) { return e.reinitialised; }},
    {"source_present", [](const engine::Estimate& e) { return e.source_present; }},
    {"ambiguous", [](const engine::Estimate& e) { return e.ambiguous; }},
    {"far_field", [](const engine::Estimate& e) { return e.far_field; }},
};

}  // namespace

py::dtype EstimateDtype(int pair_count) {
  std::vector<Column> columns = {{"frame_index", "<u8", {}}, {"sequence", "<u8", {}}};
  for (const DoubleColumn& c : kDoubleColumns) columns.push_back({c.name, "<f8", {}});
  for (const BoolColumn& c : kBoolColumns) columns.push_back({c.name, "?", {}});
  columns.push_back({"modes", "<i4", {}});
  columns.push_back({"pairs_used", "<i4", {}});
  columns.push_back({"covariance", "<f8", {6, 6}});  // (x, y, z, vx, vy, vz): m, m/s
  if (pair_count > 0) {
    columns.push_back({"delay_s", "<f8", {pair_count}});
    columns.push_back({"quality", "<f8", {pair_count}});
  }
  return RecordDtype(columns);
}

py::array EstimatesToArray(const std::vector<engine::Estimate>& estimates, int pair_count) {
  RecordWriter out(EstimateDtype(pair_count), estimates.size());
  std::vector<size_t> double_at, bool_at;
  for (const DoubleColumn& c : kDoubleColumns) double_at.push_back(out.Offset(c.name));
  for (const BoolColumn& c : kBoolColumns) bool_at.push_back(out.Offset(c.name));
  const size_t frame_at = out.Offset("frame_index"), sequence_at = out.Offset("sequence");
  const size_t modes_at = out.Offset("modes"), pairs_at = out.Offset("pairs_used");
  const size_t covariance_at = out.Offset("covariance");
  const size_t delay_at = pair_count > 0 ? out.Offset("delay_s") : 0;
  const size_t quality_at = pair_count > 0 ? out.Offset("quality") : 0;
  const std::vector<double> missing(static_cast<size_t>(std::max(pair_count, 0)), NAN);
  for (size_t row = 0; row < estimates.size(); ++row) {
    const engine::Estimate& e = estimates[row];
    out.Set<uint64_t>(row, frame_at, e.frame_index);
    out.Set<uint64_t>(row, sequence_at, e.sequence);
    for (size_t k = 0; k < double_at.size(); ++k) out.Set<double>(row, double_at[k], kDoubleColumns[k].get(e));
    for (size_t k = 0; k < bool_at.size(); ++k) out.Set<bool>(row, bool_at[k], kBoolColumns[k].get(e));
    out.Set<int32_t>(row, modes_at, e.modes);
    out.Set<int32_t>(row, pairs_at, e.pairs_used);
    // Row-major, as numpy reads a C-ordered (6, 6) subarray; Eigen's storage is column-major.
    const Eigen::Matrix<double, 6, 6, Eigen::RowMajor> covariance = e.covariance;
    out.SetMany(row, covariance_at, covariance.data(), 36);
    if (pair_count > 0) {
      // A frame without pair measurements (none made yet) reads NaN, as estimates.csv.
      const bool has_pairs =
          static_cast<int>(e.delay_s.size()) == pair_count && static_cast<int>(e.quality.size()) == pair_count;
      out.SetMany(row, delay_at, has_pairs ? e.delay_s.data() : missing.data(), missing.size());
      out.SetMany(row, quality_at, has_pairs ? e.quality.data() : missing.data(), missing.size());
    }
  }
  return out.array();
}

py::dtype SourceDtype() {
  return RecordDtype({{"frame_index", "<u8", {}},
                      {"t_s", "<f8", {}},
                      {"source_id", "<u8", {}},
                      {"status", "<U10", {}},  // tentative | confirmed | coasting
                      {"source_present", "?", {}},
                      {"azimuth_rad", "<f8", {}},
                      {"elevation_rad", "<f8", {}},
                      {"cone_angle_rad", "<f8", {}},
                      {"sigma_rad", "<f8", {}},
                      {"power_db", "<f8", {}},
                      {"direction", "<f8", {3}},
                      {"position_m", "<f8", {3}},
                      {"range_sd_m", "<f8", {}}});
}

py::array SourcesToArray(const std::vector<engine::Estimate>& estimates) {
  size_t rows = 0;
  for (const engine::Estimate& e : estimates) rows += e.sources.size();
  RecordWriter out(SourceDtype(), rows);
  const size_t frame_at = out.Offset("frame_index"), t_at = out.Offset("t_s"), id_at = out.Offset("source_id");
  const size_t status_at = out.Offset("status"), present_at = out.Offset("source_present");
  const size_t azimuth_at = out.Offset("azimuth_rad"), elevation_at = out.Offset("elevation_rad");
  const size_t cone_at = out.Offset("cone_angle_rad"), sigma_at = out.Offset("sigma_rad");
  const size_t power_at = out.Offset("power_db"), direction_at = out.Offset("direction");
  const size_t position_at = out.Offset("position_m"), range_at = out.Offset("range_sd_m");
  size_t row = 0;
  for (const engine::Estimate& e : estimates) {
    for (const engine::SourceEstimate& s : e.sources) {
      out.Set<uint64_t>(row, frame_at, e.frame_index);
      out.Set<double>(row, t_at, e.t_s);
      out.Set<uint64_t>(row, id_at, s.source_id);
      // numpy's "U" is UCS-4: one uint32 per character, zero padded (the row is zeroed).
      const std::string status = engine::TrackStatusName(s.status);
      for (size_t k = 0; k < status.size() && k < 10; ++k) {
        out.Set<uint32_t>(row, status_at + 4 * k, static_cast<uint32_t>(status[k]));
      }
      out.Set<bool>(row, present_at, s.source_present);
      out.Set<double>(row, azimuth_at, s.azimuth_rad);
      out.Set<double>(row, elevation_at, s.elevation_rad);
      out.Set<double>(row, cone_at, s.cone_angle_rad);
      out.Set<double>(row, sigma_at, s.sigma_rad);
      out.Set<double>(row, power_at, s.power_db);
      out.SetMany(row, direction_at, s.direction.data(), 3);
      out.SetMany(row, position_at, s.position_m.data(), 3);
      out.Set<double>(row, range_at, s.range_sd_m);
      ++row;
    }
  }
  return out.array();
}

}  // namespace localizer::python
