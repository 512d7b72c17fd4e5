// Truth and estimate tables as CSV.
//
// truth.csv (one row per truth sample, t_s ascending):
//   t_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps
// t_s is reception time at the reference sensor, seconds from the first sample; the state
// is the source's at the emission heard then (engine::TruthRow).
//
// estimates.csv (one row per engine::Estimate, i.e. per frame):
//   t_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,      state (same instant convention as truth)
//   sx_m,sy_m,sz_m,                            position std: sqrt of the covariance diagonal
//   ess,nis,pairs_used,tdoa_sigma_us,          filter health: pairs conditioned on, the
//   initialised,reinitialised,                 TDOA noise assumed; flags are 0 or 1
//   tdoa_ms,filter_ms,                         stage wall times of the frame
//   source_present,presence_statistic,         source presence (0 or 1) and the detection
//   presence_threshold,                        statistic and threshold behind it
//   ambiguous,modes,                           several position hypotheses (0 or 1), and
//                                              how many (1 resolved, 0 not initialised)
//   far_field,range_sd_m,                      the frame does not bound the range (0 or 1),
//                                              and the range sd its TDOAs allow (0: none)
//   delay_s_<k>,quality_<k>, ...               per sensor pair (reference, k), k ascending
// Missing per-pair values are written as nan. Readers look columns up by name, so extra
// columns are ignored; files written before the presence columns existed still read.
#pragma once

#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "clients/io/estimates_writer.h"
#include "engine/core/estimate.h"
#include "engine/core/status.h"
#include "engine/sim/simulator.h"

namespace localizer::io {

inline constexpr const char* kStateColumns = "t_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps";

Status WriteTruthCsv(const std::string& path, const std::vector<engine::TruthRow>& truth);
StatusOr<std::vector<engine::TruthRow>> ReadTruthCsv(const std::string& path);

// The columns of estimates.csv that scoring needs.
struct EstimateRow {
  double t_s = 0.0;
  engine::Vec3 position_m = engine::Vec3::Zero();
  engine::Vec3 velocity_mps = engine::Vec3::Zero();
  bool initialised = false;
  // Presence columns; unset when the file predates them.
  std::optional<bool> source_present = std::nullopt;
  double presence_statistic = 0.0;
  double presence_threshold = 0.0;
  bool ambiguous = false;
  int modes = 0;
};

StatusOr<std::vector<EstimateRow>> ReadEstimatesCsv(const std::string& path);

// Writes estimates.csv row by row, so a long run can stream to disk. Movable.
class EstimatesCsvWriter final : public EstimatesWriter {
 public:
  // `pair_sensors[p]`: the non-reference sensor of pair p (ArrayGeometry::sensor_of_pair).
  static StatusOr<EstimatesCsvWriter> Open(const std::string& path, const std::vector<int>& pair_sensors);
  // Sessions that list sources (directions; positions from planar and linear arrays): one
  // row per (frame, source) of Estimate::sources, or one row with an empty source_id for a
  // frame that has none:
  //     t_s,frame,source_id,status,source_present,azimuth_rad,elevation_rad,cone_angle_rad,
  //     sigma_rad,power_db,x_m,y_m,z_m,frame_source_present,presence_statistic,
  //     presence_threshold,tdoa_ms,range_sd_m
  // A field the array cannot observe is empty (azimuth and elevation for a line, the cone
  // angle otherwise; x_m, y_m, z_m unless the session gives positions and the frame bounds
  // the source's range; range_sd_m where a near-field fit was made). frame_source_present
  // says whether any source was heard on the frame; source_present whether this one was.
  static StatusOr<EstimatesCsvWriter> OpenSources(const std::string& path);
  Status Write(const engine::Estimate& estimate) override;
  // Flushes and closes; reports a failed write that the stream only notices at the end.
  Status Close() override;

 private:
  EstimatesCsvWriter() = default;
  std::string path_;
  size_t pair_count_ = 0;
  bool sources_ = false;  // OpenSources' layout
  std::unique_ptr<std::ofstream> out_;
  std::string line_;  // reused per row
};

}  // namespace localizer::io
