// Accuracy over seeds: every named scenario, both likelihoods, seeds 1..N; prints each run
// and the median RMSE / per-frame CRLB and p95 / RMSE per scenario (BENCHMARKS.md).
// Run: build/tests/bench/accuracy_report [N=5] [--one-std] [--levels FLOOR,CEILING,HZ]
//        [--turns MAX] [--speed-changes MAX] [--cross-pairs N] [--delay-rates 0|1]
//        [--closure 0|1] [--fusion 0|1]
// --one-std: the particle filter with one acceleration std, no turn rates and no speed changes
// (SetSingleMotion); --levels: these acceleration levels instead of the defaults
// (particle_filter.h); --turns: per-particle turn rates up to MAX rad/s; --speed-changes:
// per-particle speed changes up to MAX m/s^2 (ParticleFilterOptions); --cross-pairs: the
// session's cross_pairs_max_sensors (0: acquisition searches the reference pairs only);
// --delay-rates: the session's delay_rate_compensation (0: channels read as they are);
// --closure: the session's pair_closure (0: tracked frames use the reference pairs as measured).
// --fusion: the session's pair_fusion (0: the reference pairs' delays are not fused with the others).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <tuple>

#include "engine/core/flags.h"
#include "engine/pipeline/session.h"
#include "engine/sim/evaluation.h"
#include "tests/pipeline/scenario_run.h"

namespace localizer::engine {
namespace {

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

}  // namespace
}  // namespace localizer::engine

int main(int argc, char** argv) {
  using namespace localizer::engine;
  int seeds = 5;
  bool one_std = false;
  double floor = -1.0, ceiling = -1.0, switch_hz = -1.0, turns = -1.0, speed_changes = -1.0;
  int cross_pairs = -1;  // < 0: the session's default
  int delay_rates = -1;  // < 0: the session's default
  int closure = -1;      // < 0: the session's default
  int fusion = -1;       // < 0: the session's default
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--one-std") {
      one_std = true;
    } else if (arg == "--levels" && has_value) {
      if (std::sscanf(argv[++i], "%lf,%lf,%lf", &floor, &ceiling, &switch_hz) != 3) {
        std::fprintf(stderr, "accuracy_report: --levels takes FLOOR,CEILING,HZ, got \"%s\"\n", argv[i]);
        return 2;
      }
    } else if (arg == "--turns" && has_value) {
      turns = std::strtod(argv[++i], nullptr);
    } else if (arg == "--speed-changes" && has_value) {
      speed_changes = std::strtod(argv[++i], nullptr);
    } else if (arg == "--cross-pairs" && has_value) {
      cross_pairs = std::atoi(argv[++i]);
    } else if (arg == "--delay-rates" && has_value) {
      delay_rates = std::atoi(argv[++i]) != 0 ? 1 : 0;
    } else if (arg == "--closure" && has_value) {
      closure = std::atoi(argv[++i]) != 0 ? 1 : 0;
    } else if (arg == "--fusion" && has_value) {
      fusion = std::atoi(argv[++i]) != 0 ? 1 : 0;
    } else {
      const auto n = localizer::ParseInteger(arg);
      if (!n.ok() || *n < 1 || *n > 1000000) {
        std::fprintf(
            stderr,
            "usage: accuracy_report [N=5] [--one-std] [--levels FLOOR,CEILING,HZ] [--turns MAX] "
            "[--speed-changes MAX] [--cross-pairs N] [--delay-rates 0|1] [--closure 0|1] [--fusion 0|1]\n(N must be an integer in [1, "
            "1000000], got \"%s\")\n",
            arg.c_str());
        return 2;
      }
      seeds = static_cast<int>(*n);
    }
  }
  std::printf("%-16s %-5s %5s %8s %8s %8s %8s %7s %6s\n", "scenario", "lik", "seed", "rmse_m", "p95_m", "crlb_m",
              "ratio", "p95/rmse", "reinit");
  for (const std::string& name : ScenarioNames()) {
    for (Likelihood likelihood : {Likelihood::kPeak, Likelihood::kGcc}) {
      std::vector<double> ratios, tails;
      for (int seed = 1; seed <= seeds; ++seed) {
        const auto adjust = [&](AudioSessionConfig* c) {
          ParticleFilterOptions& p = c->tracker.particle;
          if (one_std) p.SetSingleMotion();
          if (floor > 0.0)
            std::tie(p.accel_level_floor, p.accel_level_ceiling, p.accel_level_switch_hz) =
                std::tuple(floor, ceiling, switch_hz);
          if (turns >= 0.0) p.turn_rate_max_radps = turns;
          if (speed_changes >= 0.0) p.speed_change_max_mps2 = speed_changes;
          if (cross_pairs >= 0) c->cross_pairs_max_sensors = cross_pairs;
          if (delay_rates >= 0) c->delay_rate_compensation = delay_rates == 1;
          if (closure >= 0) c->pair_closure = closure == 1;
          if (fusion >= 0) c->pair_fusion = fusion == 1;
        };
        const TrackScore s = TrackScenario(name, static_cast<uint64_t>(seed), likelihood, BackendChoice::kCpu,
                                           FilterKind::kPf, MotionModelKind::kCv, adjust)
                                 .score;
        std::printf("%-16s %-5s %5d %8.3f %8.3f %8.3f %8.3f %7.2f %6d\n", name.c_str(), LikelihoodName(likelihood),
                    seed, s.rmse_m, s.p95_m, s.crlb_m, s.rmse_over_crlb, s.p95_m / s.rmse_m, s.reinitialisations);
        ratios.push_back(s.rmse_over_crlb);
        tails.push_back(s.p95_m / s.rmse_m);
      }
      std::printf("%-16s %-5s median rmse/crlb %.3f  median p95/rmse %.2f\n", name.c_str(), LikelihoodName(likelihood),
                  Median(ratios), Median(tails));
    }
  }
}
