// Estimates as JSON lines: one JSON object per engine::Estimate, one per line, written as
// they come (`localizer-cli track --format jsonl`). For tools that read records, not tables
// (jq, pandas.read_json(lines=True), log shippers); the CSV (csv_io.h) stays the default.
//
// Each line holds, in SI units with the names of engine/core/estimate.h:
//   frame, t_s, initialised, reinitialised, source_present, presence_statistic,
//   presence_threshold, ambiguous, modes, far_field, range_sd_m, nis, ess, pairs_used,
//   tdoa_sigma_s, tdoa_ms, filter_ms,
//   position_m [x, y, z], velocity_mps [vx, vy, vz], position_sd_m [sx, sy, sz] and
//   covariance (6 x 6, row-major nested arrays): present only once initialised;
//   pairs: [{"sensor": k, "delay_s": d, "quality": q}, ...] (pair (reference, k));
//   model_probabilities: {"cv": p, ...} (multiple-model filters only);
//   sources: [{"source_id", "status", "source_present", "azimuth_rad", "elevation_rad",
//              "cone_angle_rad", "sigma_rad", "power_db", "position_m", "range_sd_m"}]
//              (sessions that list sources; a field the array cannot observe is null).
// JSON has no NaN or infinity: a non-finite number is written as null.
#pragma once

#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "clients/io/estimates_writer.h"

namespace localizer::io {

class EstimatesJsonlWriter final : public EstimatesWriter {
 public:
  // `pair_sensors[p]`: the non-reference sensor of pair p (empty for source sessions).
  static StatusOr<std::unique_ptr<EstimatesJsonlWriter>> Open(const std::string& path, std::vector<int> pair_sensors);
  Status Write(const engine::Estimate& estimate) override;
  Status Close() override;

 private:
  EstimatesJsonlWriter() = default;
  std::string path_;
  std::vector<int> pair_sensors_;
  std::unique_ptr<std::ofstream> out_;
};

// One estimate as the JSON object of a line (no newline), for the writer and for tests.
std::string EstimateJsonLine(const engine::Estimate& estimate, const std::vector<int>& pair_sensors);

}  // namespace localizer::io
