// localizer-cli attitude / attitude-score: orientation from an IMU recording, and its error
// against the recording's motion-capture truth the BROAD benchmark's way.
#include <cmath>
#include <cstdio>
#include <iostream>

#include "clients/cli/commands.h"
#include "clients/io/imu_csv.h"
#include "engine/attitude/attitude_error.h"
#include "engine/attitude/attitude_filter.h"

namespace localizer::cli {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

// Pairs each estimate with the IMU row at the same t_s (both ascending; 1 µs tolerance,
// relative beyond 1 s, as the CSVs carry 10 significant digits).
Status MatchByTime(const io::ImuRecording& imu, const std::vector<io::OrientationRow>& rows,
                   std::vector<Eigen::Quaterniond>* estimates, std::vector<Eigen::Quaterniond>* truth,
                   std::vector<bool>* scored) {
  size_t j = 0;
  for (const io::OrientationRow& row : rows) {
    const double tolerance_s = 1e-6 * std::max(1.0, std::abs(row.t_s));
    while (j < imu.samples.size() && imu.samples[j].t_s < row.t_s - tolerance_s) ++j;
    if (j == imu.samples.size() || std::abs(imu.samples[j].t_s - row.t_s) > tolerance_s) {
      char t[32];
      std::snprintf(t, sizeof t, "%.10g", row.t_s);
      return InvalidArgument(std::string("estimate at t_s=") + t + " has no IMU sample at the same time");
    }
    estimates->push_back(row.body_to_world);
    truth->push_back(imu.truth[j]);
    scored->push_back(imu.movement[j]);
  }
  return Status::Ok();
}

}  // namespace

int RunAttitude(const std::vector<std::string>& args) {
  const std::string command = "attitude";
  std::string imu_path;
  std::string out_path;
  std::string filter_name = "quaternion";
  bool use_mag = false;
  FlagSet flags("localizer-cli attitude --imu FILE --out FILE [--mag] [--filter quaternion|euler]",
                "Estimates the IMU's orientation (body -> East-North-Up) at every sample with the\n"
                "default parameter set, and writes one row per sample:\n"
                "t_s,qw,qx,qy,qz,roll_rad,pitch_rad,yaw_rad,roll_sd_rad,pitch_sd_rad,yaw_sd_rad.\n"
                "Without --mag, yaw is relative to the heading at the first sample.");
  flags.String("imu", &imu_path, "FILE", "IMU CSV: t_s, gyr_{x,y,z}_rps, acc_{x,y,z}_mps2 [, mag_{x,y,z}_uT]")
      .Required();
  flags.String("out", &out_path, "FILE", "orientation CSV to write").Required();
  flags.Bool("mag", &use_mag, "correct heading with the magnetometer (needs mag_* columns)");
  flags.String("filter", &filter_name, "NAME",
               "quaternion (multiplicative EKF with gyro bias; default) or euler (the seed's "
               "roll/pitch/yaw EKF, singular at +-90 deg pitch)");
  if (auto exit_code = ParseFlagsOrExit(command, flags, args)) return *exit_code;
  auto kind = engine::ParseAttitudeFilterKind(filter_name);
  if (!kind.ok()) return UsageError(command, "--filter: " + kind.status().message());

  auto imu = io::ReadImuCsv(imu_path, use_mag, /*need_truth=*/false);
  if (!imu.ok()) return RuntimeError(command, imu.status());
  engine::AttitudeFilterOptions options;
  options.kind = *kind;
  options.use_mag = use_mag;
  auto filter = engine::CreateAttitudeFilter(options);
  if (!filter.ok()) return RuntimeError(command, filter.status());
  std::vector<engine::AttitudeEstimate> estimates;
  estimates.reserve(imu->samples.size());
  for (const engine::ImuSample& sample : imu->samples) {
    const Status status = (*filter)->Update(sample);
    if (!status.ok()) {
      return RuntimeError(command, Status(status.code(), imu_path + ": " + status.message()));
    }
    estimates.push_back((*filter)->estimate());
  }
  const Status written = io::WriteOrientationCsv(out_path, estimates);
  if (!written.ok()) return RuntimeError(command, written);
  return kExitOk;
}

int RunAttitudeScore(const std::vector<std::string>& args) {
  const std::string command = "attitude-score";
  std::string imu_path;
  std::string estimates_path;
  FlagSet flags("localizer-cli attitude-score --imu FILE --estimates FILE",
                "Scores an orientation CSV against the IMU CSV's truth the BROAD benchmark's way:\n"
                "q_err = q_est * q_truth^-1; total = 2 acos|w|, heading = 2 atan|z/w|, inclination =\n"
                "2 acos sqrt(w^2 + z^2); RMS over rows with movement = 1 and finite truth. No heading\n"
                "alignment is applied. Prints n=..., total_rmse_deg=..., heading_rmse_deg=...,\n"
                "inclination_rmse_deg=.... Estimates are matched to IMU rows by t_s.");
  flags.String("imu", &imu_path, "FILE", "IMU CSV with truth_q{w,x,y,z} (NaN where unknown) and movement columns")
      .Required();
  flags.String("estimates", &estimates_path, "FILE", "orientation CSV written by attitude").Required();
  if (auto exit_code = ParseFlagsOrExit(command, flags, args)) return *exit_code;

  auto imu = io::ReadImuCsv(imu_path, /*need_mag=*/false, /*need_truth=*/true);
  if (!imu.ok()) return RuntimeError(command, imu.status());
  auto rows = io::ReadOrientationCsv(estimates_path);
  if (!rows.ok()) return RuntimeError(command, rows.status());
  std::vector<Eigen::Quaterniond> estimates, truth;
  std::vector<bool> scored;
  if (const Status matched = MatchByTime(*imu, *rows, &estimates, &truth, &scored); !matched.ok()) {
    return RuntimeError(command, Status(matched.code(), estimates_path + " vs " + imu_path + ": " + matched.message()));
  }
  auto score = engine::ScoreAttitude(estimates, truth, scored);
  if (!score.ok()) {
    return RuntimeError(
        command, Status(score.status().code(), estimates_path + " vs " + imu_path + ": " + score.status().message()));
  }
  char line[160];
  std::snprintf(line, sizeof line, "n=%ld, total_rmse_deg=%.3f, heading_rmse_deg=%.3f, inclination_rmse_deg=%.3f",
                static_cast<long>(score->count), score->total_rmse_rad * kRadToDeg, score->heading_rmse_rad * kRadToDeg,
                score->inclination_rmse_rad * kRadToDeg);
  std::cout << line << "\n";
  return kExitOk;
}

}  // namespace localizer::cli
