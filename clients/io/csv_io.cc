#include "clients/io/csv_io.h"

#include <array>
#include <cmath>

#include "clients/io/csv_table.h"

namespace localizer::io {

namespace {

constexpr std::array<const char*, 7> kStateNames = {"t_s", "x_m", "y_m", "z_m", "vx_mps", "vy_mps", "vz_mps"};

void AppendRow(const std::vector<double>& values, std::string* line) {
  line->clear();
  for (size_t i = 0; i < values.size(); ++i) {
    if (i > 0) line->push_back(',');
    AppendNumber(values[i], line);
  }
  line->push_back('\n');
}

// Column indices of the 7 state columns, in kStateNames order.
StatusOr<std::array<int, 7>> StateColumns(const CsvTable& table) {
  std::array<int, 7> columns{};
  for (size_t i = 0; i < kStateNames.size(); ++i) {
    auto column = table.Column(kStateNames[i]);
    if (!column.ok()) return column.status();
    columns[i] = *column;
  }
  return columns;
}

// Reads the 7 state values of one row: t_s, position, velocity.
StatusOr<std::array<double, 7>> StateValues(const CsvTable& table, size_t row, const std::array<int, 7>& columns) {
  std::array<double, 7> values{};
  for (size_t i = 0; i < columns.size(); ++i) {
    auto value = table.Number(row, columns[i]);
    if (!value.ok()) return value.status();
    values[i] = *value;
  }
  return values;
}

}  // namespace

Status WriteTruthCsv(const std::string& path, const std::vector<engine::TruthRow>& truth) {
  std::ofstream out(path);
  if (!out) return InvalidArgument(path + ": cannot open for writing");
  out << kStateColumns << "\n";
  std::string line;
  for (const engine::TruthRow& row : truth) {
    const engine::Vec3& p = row.position_m;
    const engine::Vec3& v = row.velocity_mps;
    AppendRow({row.t_s, p.x(), p.y(), p.z(), v.x(), v.y(), v.z()}, &line);
    out << line;
  }
  out.close();
  if (!out) return InvalidArgument(path + ": write failed");
  return Status::Ok();
}

StatusOr<std::vector<engine::TruthRow>> ReadTruthCsv(const std::string& path) {
  auto table = CsvTable::Read(path);
  if (!table.ok()) return table.status();
  auto columns = StateColumns(*table);
  if (!columns.ok()) return columns.status();
  std::vector<engine::TruthRow> truth;
  for (size_t r = 0; r < table->row_count(); ++r) {
    auto v = StateValues(*table, r, *columns);
    if (!v.ok()) return v.status();
    engine::TruthRow row;
    row.t_s = (*v)[0];
    row.position_m = engine::Vec3((*v)[1], (*v)[2], (*v)[3]);
    row.velocity_mps = engine::Vec3((*v)[4], (*v)[5], (*v)[6]);
    truth.push_back(row);
  }
  return truth;
}

StatusOr<std::vector<EstimateRow>> ReadEstimatesCsv(const std::string& path) {
  auto table = CsvTable::Read(path);
  if (!table.ok()) return table.status();
  auto columns = StateColumns(*table);
  if (!columns.ok()) return columns.status();
  auto initialised_column = table->Column("initialised");
  if (!initialised_column.ok()) return initialised_column.status();
  // Presence columns: files written before they existed have none (the row's presence
  // then stays unknown); a file must have all or none of them.
  const char* presence_names[5] = {"source_present", "presence_statistic", "presence_threshold", "ambiguous", "modes"};
  int presence_columns[5];
  int found = 0;
  for (int i = 0; i < 5; ++i) {
    auto column = table->Column(presence_names[i]);
    presence_columns[i] = column.ok() ? *column : -1;
    if (column.ok()) ++found;
  }
  if (found != 0 && found != 5) {
    for (int i = 0; i < 5; ++i) {
      if (presence_columns[i] < 0) return table->Column(presence_names[i]).status();
    }
  }
  std::vector<EstimateRow> estimates;
  for (size_t r = 0; r < table->row_count(); ++r) {
    auto v = StateValues(*table, r, *columns);
    if (!v.ok()) return v.status();
    auto initialised = table->Number(r, *initialised_column);
    if (!initialised.ok()) return initialised.status();
    EstimateRow row;
    row.t_s = (*v)[0];
    row.position_m = engine::Vec3((*v)[1], (*v)[2], (*v)[3]);
    row.velocity_mps = engine::Vec3((*v)[4], (*v)[5], (*v)[6]);
    row.initialised = *initialised != 0.0;
    if (found == 5) {
      double presence[5];
      for (int i = 0; i < 5; ++i) {
        auto value = table->Number(r, presence_columns[i]);
        if (!value.ok()) return value.status();
        presence[i] = *value;
      }
      row.source_present = presence[0] != 0.0;
      row.presence_statistic = presence[1];
      row.presence_threshold = presence[2];
      row.ambiguous = presence[3] != 0.0;
      // A count: a whole number that fits an int (a cast of NaN or 1e300 is undefined).
      if (!(presence[4] >= 0.0 && presence[4] <= 1e9 && presence[4] == std::floor(presence[4]))) {
        return InvalidArgument(table->path() + ": data row " + std::to_string(r + 1) + ", column modes: value " +
                               table->Text(r, presence_columns[4]) + " is not a whole number in [0, 1e9]");
      }
      row.modes = static_cast<int>(presence[4]);
    }
    estimates.push_back(row);
  }
  return estimates;
}

StatusOr<EstimatesCsvWriter> EstimatesCsvWriter::Open(const std::string& path, const std::vector<int>& pair_sensors) {
  EstimatesCsvWriter writer;
  writer.path_ = path;
  writer.pair_count_ = pair_sensors.size();
  writer.out_ = std::make_unique<std::ofstream>(path);
  if (!*writer.out_) return InvalidArgument(path + ": cannot open for writing");
  std::string header = std::string(kStateColumns) +
                       ",sx_m,sy_m,sz_m,ess,nis,pairs_used,tdoa_sigma_us,initialised,reinitialised,tdoa_ms,filter_ms,"
                       "source_present,presence_statistic,presence_threshold,ambiguous,modes,far_field,range_sd_m";
  for (int k : pair_sensors) {
    header += ",delay_s_" + std::to_string(k) + ",quality_" + std::to_string(k);
  }
  *writer.out_ << header << "\n";
  return writer;
}

StatusOr<EstimatesCsvWriter> EstimatesCsvWriter::OpenSources(const std::string& path) {
  EstimatesCsvWriter writer;
  writer.path_ = path;
  writer.sources_ = true;
  writer.out_ = std::make_unique<std::ofstream>(path);
  if (!*writer.out_) return InvalidArgument(path + ": cannot open for writing");
  *writer.out_ << "t_s,frame,source_id,status,source_present,azimuth_rad,elevation_rad,cone_angle_rad,sigma_rad,"
                  "power_db,x_m,y_m,z_m,frame_source_present,presence_statistic,presence_threshold,tdoa_ms,range_sd_m\n";
  return writer;
}

namespace {

void AppendSourceRow(const engine::Estimate& e, const engine::SourceEstimate* s, std::string* line) {
  line->clear();
  AppendNumber(e.t_s, line);
  line->push_back(',');
  line->append(std::to_string(e.frame_index));
  line->push_back(',');
  if (s != nullptr) {
    line->append(std::to_string(s->source_id));
    line->push_back(',');
    line->append(engine::TrackStatusName(s->status));
    line->append(s->source_present ? ",1" : ",0");
    for (double v : {s->azimuth_rad, s->elevation_rad, s->cone_angle_rad, s->sigma_rad, s->power_db}) {
      AppendField(v, line);
    }
  } else {
    line->append(",,,,,,,");  // status .. power_db
  }
  const double nan = engine::SourceEstimate::kNan;
  const engine::Vec3 position_m = s != nullptr ? s->position_m : engine::Vec3::Constant(nan);  // NaN: not bounded
  for (int axis = 0; axis < 3; ++axis) AppendField(position_m[axis], line);
  line->append(e.source_present ? ",1" : ",0");
  for (double v : {e.presence_statistic, e.presence_threshold, e.timings.tdoa_s * 1e3}) AppendField(v, line);
  AppendField(s != nullptr ? s->range_sd_m : nan, line);
  line->push_back('\n');
}

}  // namespace

Status EstimatesCsvWriter::Write(const engine::Estimate& e) {
  if (!out_) return FailedPrecondition(path_ + ": writer is closed");
  if (sources_) {
    if (e.sources.empty()) {
      AppendSourceRow(e, nullptr, &line_);
      *out_ << line_;
    }
    for (const engine::SourceEstimate& s : e.sources) {
      AppendSourceRow(e, &s, &line_);
      *out_ << line_;
    }
    if (!*out_) return InvalidArgument(path_ + ": write failed");
    return Status::Ok();
  }
  const engine::Vec6& s = e.state;
  std::vector<double> values = {e.t_s, s[0], s[1], s[2], s[3], s[4], s[5]};
  for (int axis = 0; axis < 3; ++axis) {
    values.push_back(std::sqrt(std::max(0.0, e.covariance(axis, axis))));
  }
  values.insert(values.end(), {e.ess, e.nis, static_cast<double>(e.pairs_used), e.tdoa_sigma_s * 1e6,
                               e.initialised ? 1.0 : 0.0, e.reinitialised ? 1.0 : 0.0, e.timings.tdoa_s * 1e3,
                               e.timings.filter_s * 1e3, e.source_present ? 1.0 : 0.0, e.presence_statistic,
                               e.presence_threshold, e.ambiguous ? 1.0 : 0.0, static_cast<double>(e.modes),
                               e.far_field ? 1.0 : 0.0, e.range_sd_m});
  for (size_t p = 0; p < pair_count_; ++p) {
    values.push_back(p < e.delay_s.size() ? e.delay_s[p] : NAN);
    values.push_back(p < e.quality.size() ? e.quality[p] : NAN);
  }
  AppendRow(values, &line_);
  *out_ << line_;
  if (!*out_) return InvalidArgument(path_ + ": write failed");
  return Status::Ok();
}

Status EstimatesCsvWriter::Close() { return CloseOutput(&out_, path_); }

}  // namespace localizer::io
