#include "clients/io/imu_csv.h"

#include <array>
#include <cmath>
#include <fstream>

#include "clients/io/csv_table.h"

namespace localizer::io {
namespace {

template <size_t N>
StatusOr<std::array<int, N>> Columns(const CsvTable& table, const std::array<const char*, N>& names) {
  std::array<int, N> columns{};
  for (size_t i = 0; i < N; ++i) {
    auto column = table.Column(names[i]);
    if (!column.ok()) return column.status();
    columns[i] = *column;
  }
  return columns;
}

// The value at (row, column), finite unless allow_nan (then NaN is fine but not +-inf).
StatusOr<double> Value(const CsvTable& table, size_t row, int column, bool allow_nan) {
  auto value = table.Number(row, column);
  if (!value.ok()) return value.status();
  if (!std::isfinite(*value) && !(allow_nan && std::isnan(*value))) {
    return InvalidArgument(table.path() + ": data row " + std::to_string(row + 1) + ", column " +
                           table.header()[static_cast<size_t>(column)] + ": value " + table.Text(row, column) +
                           " is not finite");
  }
  return *value;
}

template <size_t N>
Status ReadRow(const CsvTable& table, size_t row, const std::array<int, N>& columns, bool allow_nan, double* out) {
  for (size_t i = 0; i < N; ++i) {
    auto value = Value(table, row, columns[i], allow_nan);
    if (!value.ok()) return value.status();
    out[i] = *value;
  }
  return Status::Ok();
}

Status CheckIncreasing(const CsvTable& table, size_t row, int column, double t_s, double previous_t_s) {
  if (row > 0 && !(t_s > previous_t_s)) {
    return InvalidArgument(table.path() + ": data row " + std::to_string(row + 1) + ": t_s " + table.Text(row, column) +
                           " is not after the previous row's");
  }
  return Status::Ok();
}

}  // namespace

StatusOr<ImuRecording> ReadImuCsv(const std::string& path, bool need_mag, bool need_truth) {
  auto table = CsvTable::Read(path);
  if (!table.ok()) return table.status();
  auto imu =
      Columns<7>(*table, {"t_s", "gyr_x_rps", "gyr_y_rps", "gyr_z_rps", "acc_x_mps2", "acc_y_mps2", "acc_z_mps2"});
  if (!imu.ok()) return imu.status();
  ImuRecording recording;
  std::array<int, 3> mag{};
  if (auto columns = Columns<3>(*table, {"mag_x_uT", "mag_y_uT", "mag_z_uT"}); columns.ok()) {
    mag = *columns;
    recording.has_mag = true;
  } else if (need_mag) {
    return InvalidArgument(columns.status().message() + " (the magnetometer is asked for)");
  }
  std::array<int, 5> truth{};
  if (need_truth) {
    auto columns = Columns<5>(*table, {"truth_qw", "truth_qx", "truth_qy", "truth_qz", "movement"});
    if (!columns.ok()) return columns.status();
    truth = *columns;
  }
  const size_t rows = table->row_count();
  if (rows == 0) return InvalidArgument(path + ": no data rows");
  recording.samples.reserve(rows);
  double previous_t_s = 0.0;
  for (size_t r = 0; r < rows; ++r) {
    double v[7];
    LOCALIZER_RETURN_IF_ERROR(ReadRow(*table, r, *imu, /*allow_nan=*/false, v));
    LOCALIZER_RETURN_IF_ERROR(CheckIncreasing(*table, r, (*imu)[0], v[0], previous_t_s));
    previous_t_s = v[0];
    engine::ImuSample s;
    s.t_s = v[0];
    s.gyro_rps = {v[1], v[2], v[3]};
    s.accel_mps2 = {v[4], v[5], v[6]};
    if (recording.has_mag) {
      double m[3];
      // A missing field (NaN) on some rows is allowed: those samples get no mag update.
      LOCALIZER_RETURN_IF_ERROR(ReadRow(*table, r, mag, /*allow_nan=*/true, m));
      s.mag_uT = {m[0], m[1], m[2]};
    }
    recording.samples.push_back(s);
    if (need_truth) {
      double q[5];
      LOCALIZER_RETURN_IF_ERROR(ReadRow(*table, r, truth, /*allow_nan=*/true, q));
      const Eigen::Quaterniond truth_q(q[0], q[1], q[2], q[3]);  // (w, x, y, z)
      if (truth_q.coeffs().allFinite() && std::abs(truth_q.norm() - 1.0) > 1e-3) {
        return InvalidArgument(path + ": data row " + std::to_string(r + 1) + ": truth quaternion has norm " +
                               std::to_string(truth_q.norm()) + ", expected 1");
      }
      recording.truth.push_back(truth_q);
      recording.movement.push_back(q[4] == 1.0);
    }
  }
  return recording;
}

Status WriteOrientationCsv(const std::string& path, const std::vector<engine::AttitudeEstimate>& estimates) {
  std::ofstream out(path);
  if (!out) return InvalidArgument(path + ": cannot open for writing");
  out << "t_s,qw,qx,qy,qz,roll_rad,pitch_rad,yaw_rad,roll_sd_rad,pitch_sd_rad,yaw_sd_rad\n";
  std::string line;
  for (const engine::AttitudeEstimate& e : estimates) {
    line.clear();
    const Eigen::Quaterniond& q = e.body_to_world;
    const double values[] = {e.t_s,           q.w(),           q.x(),        q.y(),        q.z(),       e.euler_rad.x(),
                             e.euler_rad.y(), e.euler_rad.z(), e.sd_rad.x(), e.sd_rad.y(), e.sd_rad.z()};
    for (size_t i = 0; i < std::size(values); ++i) {
      if (i > 0) line += ',';
      AppendNumber(values[i], &line);
    }
    line += '\n';
    out << line;
  }
  out.close();
  if (!out) return InvalidArgument(path + ": write failed");
  return Status::Ok();
}

StatusOr<std::vector<OrientationRow>> ReadOrientationCsv(const std::string& path) {
  auto table = CsvTable::Read(path);
  if (!table.ok()) return table.status();
  auto columns = Columns<5>(*table, {"t_s", "qw", "qx", "qy", "qz"});
  if (!columns.ok()) return columns.status();
  std::vector<OrientationRow> rows;
  rows.reserve(table->row_count());
  double previous_t_s = 0.0;
  for (size_t r = 0; r < table->row_count(); ++r) {
    double v[5];
    LOCALIZER_RETURN_IF_ERROR(ReadRow(*table, r, *columns, /*allow_nan=*/false, v));
    LOCALIZER_RETURN_IF_ERROR(CheckIncreasing(*table, r, (*columns)[0], v[0], previous_t_s));
    previous_t_s = v[0];
    rows.push_back({v[0], Eigen::Quaterniond(v[1], v[2], v[3], v[4])});
  }
  if (rows.empty()) return InvalidArgument(path + ": no data rows");
  return rows;
}

}  // namespace localizer::io
