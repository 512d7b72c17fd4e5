// The CSV readers of clients/io on a file's bytes (an in-memory file, fuzz_util.h). The first
// input byte picks the reader: truth.csv, estimates.csv, imu.csv (with or without the
// magnetometer and truth columns), orientation.csv, the XAV hydrophone configuration; the
// rest is the file. Accepted files hold what the readers document.
#include "clients/io/csv_io.h"
#include "clients/io/csv_table.h"
#include "clients/io/imu_csv.h"
#include "clients/io/xav_array.h"
#include "fuzz_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace localizer;
  if (size < 1) return 0;
  static fuzz::MemFile file;
  const std::string& path = file.Write(data + 1, size - 1);
  auto table = io::CsvTable::Read(path);
  if (!table.ok()) FUZZ_CHECK(table.status().code() == StatusCode::kInvalidArgument, table.status().ToString());
  const auto expect_refused = [](const Status& status) {
    FUZZ_CHECK(status.code() == StatusCode::kInvalidArgument, status.ToString());
  };
  switch (data[0] % 8) {
    case 0: {
      auto truth = io::ReadTruthCsv(path);
      if (!truth.ok()) return expect_refused(truth.status()), 0;
      FUZZ_CHECK(table.ok() && truth->size() == table->row_count(), "row count");
      break;
    }
    case 1: {
      auto estimates = io::ReadEstimatesCsv(path);
      if (!estimates.ok()) return expect_refused(estimates.status()), 0;
      FUZZ_CHECK(table.ok() && estimates->size() == table->row_count(), "row count");
      break;
    }
    case 2:
    case 3:
    case 4:
    case 5: {
      const bool need_mag = (data[0] % 8 - 2) & 1;
      const bool need_truth = (data[0] % 8 - 2) & 2;
      auto imu = io::ReadImuCsv(path, need_mag, need_truth);
      if (!imu.ok()) return expect_refused(imu.status()), 0;
      FUZZ_CHECK(table.ok() && imu->samples.size() == table->row_count() && !imu->samples.empty(), "row count");
      FUZZ_CHECK(!need_mag || imu->has_mag, "mag");
      FUZZ_CHECK(need_truth ? imu->truth.size() == imu->samples.size() && imu->movement.size() == imu->samples.size()
                            : imu->truth.empty(),
                 "truth");
      for (size_t i = 0; i < imu->samples.size(); ++i) {
        const engine::ImuSample& s = imu->samples[i];
        FUZZ_CHECK(std::isfinite(s.t_s) && s.gyro_rps.allFinite() && s.accel_mps2.allFinite(), "non-finite");
        FUZZ_CHECK(!s.mag_uT.array().isInf().any(), "infinite mag");
        if (i > 0) FUZZ_CHECK(s.t_s > imu->samples[i - 1].t_s, "t_s not increasing");
      }
      break;
    }
    case 6: {
      auto rows = io::ReadOrientationCsv(path);
      if (!rows.ok()) return expect_refused(rows.status()), 0;
      FUZZ_CHECK(table.ok() && rows->size() == table->row_count(), "row count");
      break;
    }
    case 7: {
      // The deployment's YAML and sheet are looked up beside the file: the in-memory file has
      // none, so past the CSV's own checks the reader says NOT_FOUND naming them.
      auto xav = io::ReadXavHydrophoneCsv(path);
      if (!xav.ok() && xav.status().code() == StatusCode::kNotFound) return 0;
      if (!xav.ok()) return expect_refused(xav.status()), 0;
      FUZZ_CHECK(table.ok() && xav->array.sensors_m.size() == table->row_count(), "row count");
      FUZZ_CHECK(static_cast<size_t>(xav->array.reference_sensor) < xav->array.sensors_m.size(),
                 "reference beyond the sensors");
      FUZZ_CHECK(xav->file_name_roots.size() == xav->array.sensors_m.size(), "roots");
      break;
    }
  }
  return 0;
}
