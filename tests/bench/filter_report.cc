// Every filter through whole sessions (GCC-PHAT + tracker) on every named scenario: RMSE,
// RMSE over the per-frame position CRLB and over the posterior CRLB (the CV model's, along
// the true path: tests/pipeline/scenario_bound.h), and NEES per dimension; seeds 1..N,
// medians per (scenario, filter) last. BENCHMARKS.md quotes it.
// Run: build/tests/bench/filter_report [N=3] [filters, comma separated; default all]
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "engine/core/flags.h"
#include "tests/pipeline/scenario_bound.h"
#include "tests/pipeline/scenario_run.h"

namespace localizer::engine {
namespace {

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

struct FilterChoice {
  std::string label;  // "pf", "ekf-ct", ...
  FilterKind filter;
  MotionModelKind model;
};

// "pf,ekf-ct,..." -> the choices; an unknown name is INVALID_ARGUMENT naming it.
StatusOr<std::vector<FilterChoice>> Choices(const std::string& list) {
  std::vector<FilterChoice> all;
  std::stringstream in(list);
  for (std::string item; std::getline(in, item, ',');) {
    const auto dash = item.find('-');
    auto filter = ParseFilterKind(item.substr(0, dash), "filter");
    if (!filter.ok()) return filter.status();
    auto model = ParseMotionModelKind(dash == std::string::npos ? "cv" : item.substr(dash + 1), "motion_model");
    if (!model.ok()) return model.status();
    all.push_back({item, *filter, *model});
  }
  return all;
}

int Main(int argc, char** argv) {
  int seeds = 3;
  if (argc > 1) {
    const auto n = localizer::ParseInteger(argv[1]);
    if (!n.ok() || *n < 1 || *n > 1000000) {
      std::fprintf(stderr, "filter_report: N must be an integer in [1, 1000000], got \"%s\"\n", argv[1]);
      return 2;
    }
    seeds = static_cast<int>(*n);
  }
  const std::string list = argc > 2 ? argv[2] : "pf,ekf,ukf,ekf-ct,ukf-ct,mmpf,imm";
  std::printf("%-15s %-7s %4s %8s %9s %9s %8s %6s\n", "scenario", "filter", "seed", "rmse_m", "rmse/crlb", "rmse/pcrlb",
              "nees/dim", "reinit");
  const auto choices = Choices(list);
  if (!choices.ok()) {
    std::fprintf(stderr, "filter_report: %s\n", choices.status().ToString().c_str());
    return 2;
  }
  std::vector<std::string> summary;
  for (const std::string& name : ScenarioNames()) {
    for (const FilterChoice& f : *choices) {
      const std::string& label = f.label;
      std::vector<double> crlb, pcrlb, nees, rmse;
      for (int seed = 1; seed <= seeds; ++seed) {
        const ScenarioRun run = TrackScenario(name, seed, Likelihood::kPeak, BackendChoice::kCpu, f.filter, f.model);
        const ArrayGeometry array = *ArrayGeometry::Create(run.config.sensors_m, run.config.sound_speed_mps);
        const BoundScore b = ScoreAgainstPcrlb(array, run.sim, run.config, run.estimates, run.score, 2.0);
        std::printf("%-15s %-7s %4d %8.3f %9.3f %9.3f %8.2f %6d\n", name.c_str(), label.c_str(), seed, run.score.rmse_m,
                    run.score.rmse_over_crlb, b.rmse_over_pcrlb, b.nees_per_dim, run.score.reinitialisations);
        std::fflush(stdout);
        rmse.push_back(run.score.rmse_m);
        crlb.push_back(run.score.rmse_over_crlb);
        pcrlb.push_back(b.rmse_over_pcrlb);
        nees.push_back(b.nees_per_dim);
      }
      char line[200];
      std::snprintf(line, sizeof line, "%-15s %-7s median rmse %.3f m, rmse/crlb %.3f, rmse/pcrlb %.2f, nees/dim %.2f",
                    name.c_str(), label.c_str(), Median(rmse), Median(crlb), Median(pcrlb), Median(nees));
      summary.push_back(line);
    }
  }
  std::printf("\n");
  for (const std::string& line : summary) std::printf("%s\n", line.c_str());
  return 0;
}

}  // namespace
}  // namespace localizer::engine

int main(int argc, char** argv) { return localizer::engine::Main(argc, argv); }
