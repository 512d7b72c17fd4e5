// localizer-cli score: position error of an estimates CSV against a truth CSV.
#include <iostream>

#include "clients/cli/commands.h"
#include "clients/io/csv_io.h"
#include "clients/io/score.h"

namespace localizer::cli {

int RunScore(const std::vector<std::string>& args) {
  const std::string command = "score";
  std::string truth_path;
  std::string estimates_path;
  FlagSet flags("localizer-cli score --truth FILE --estimates FILE",
                "Scores every initialised estimate inside the truth's time span against the\n"
                "truth position interpolated linearly at its t_s (3-D error). Prints one line\n"
                "n=..., rmse_m=..., median_m=..., p95_m=..., max_m=... (p95: nearest rank).\n"
                "Exit 1 when no estimate can be scored.");
  flags.String("truth", &truth_path, "FILE", "truth CSV (t_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps)").Required();
  flags.String("estimates", &estimates_path, "FILE", "estimates CSV written by track").Required();
  if (auto exit_code = ParseFlagsOrExit(command, flags, args)) return *exit_code;

  auto truth = io::ReadTruthCsv(truth_path);
  if (!truth.ok()) return RuntimeError(command, truth.status());
  auto estimates = io::ReadEstimatesCsv(estimates_path);
  if (!estimates.ok()) return RuntimeError(command, estimates.status());
  auto score = io::Score(*truth, *estimates);
  if (!score.ok()) {
    return RuntimeError(
        command, Status(score.status().code(), truth_path + " vs " + estimates_path + ": " + score.status().message()));
  }
  std::cout << io::FormatScore(*score) << "\n";
  return kExitOk;
}

}  // namespace localizer::cli
