// The experiments of `localizer-cli experiment NAME`, each in its own cmd_experiment_*.cc;
// cmd_experiment.cc dispatches on NAME. Each takes the arguments after NAME and returns
// the exit code (commands.h: 0 ok, 1 runtime error, 2 usage error).
#pragma once

#include <string>
#include <vector>

namespace localizer::cli {

// fwl: the seed's fixed-point word-length tables (engine/experiments/fwl_study.h).
int RunFwlExperiment(const std::vector<std::string>& args);
// tws: track-while-scan on a simulated rotating radar (engine/tws/tws_tracker.h,
// engine/sim/radar_scan.h).
int RunTwsExperiment(const std::vector<std::string>& args);

}  // namespace localizer::cli
