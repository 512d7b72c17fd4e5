// localizer-cli experiment: reproduce a reference experiment and print its table.
// pf-vs-ekf-2d, the seed's particle filter against Kalman filters on a bicycle-model
// vehicle whose position fixes carry alpha-stable / Gaussian mixture noise
// (engine/experiments/pf_vs_ekf_2d.h holds the set-up and the definitions of the columns);
// fwl and tws live in cmd_experiment_fwl.cc and cmd_experiment_tws.cc, dispatched here.
#include <chrono>
#include <cstdio>
#include <functional>
#include <iostream>
#include <string>

#include "clients/cli/commands.h"
#include "clients/cli/experiment_commands.h"
#include "engine/experiments/pf_vs_ekf_2d.h"

namespace localizer::cli {
namespace {

const char* const kCommand = "experiment";
const char* const kPfVsEkf2d = "pf-vs-ekf-2d";
const char* const kFwl = "fwl";
const char* const kTws = "tws";

std::string FilterList() {
  std::string names;
  for (const std::string& name : engine::experiments::PfVsEkf2dFilterNames()) {
    names += (names.empty() ? "" : ", ") + name;
  }
  return names;
}

struct ExperimentFlags {
  engine::experiments::PfVsEkf2dOptions options;
  bool quiet = false;
};

void RegisterFlags(FlagSet& flags, ExperimentFlags& f) {
  auto& o = f.options;
  flags.Int("runs", &o.runs, "N", "", "Monte-Carlo runs");
  flags.Uint64("seed", &o.seed, "S", "experiment seed: every run's truth, fixes and particles");
  flags.Int("particles", &o.particles, "N", "", "particles of PF and PF-Gauss (seed: 100)");
  flags.Int("laps", &o.course.laps, "N", "", "laps of the closed course (seed: twice)");
  flags.Double("gaussian-sigma-m", &o.measurement_noise.gaussian_sigma_m, "M", "m",
               "std per axis of the mixture's Gaussian component (not given by the seed)");
  flags.Double("gaussian-probability", &o.measurement_noise.gaussian_probability, "E", "",
               "probability e that an axis's noise is Gaussian, else alpha-stable");
  flags.Double("stable-alpha", &o.measurement_noise.stable.alpha, "A", "",
               "tail index of the stable component, (1, 2] (the PF's density needs > 1)");
  flags.Double("stable-beta", &o.measurement_noise.stable.beta, "B", "", "skew of the stable component, [-1, 1]");
  flags.Double("stable-scale-m", &o.measurement_noise.stable.scale, "M", "m",
               "scale of the stable component (Nolan S1 gamma)");
  flags.Double("stable-location-m", &o.measurement_noise.stable.location, "M", "m",
               "location of the stable component (S1 delta: its mean; its median is lower)");
  flags.Double("speed-mps", &o.course.speed_mps, "V", "m/s", "commanded speed");
  flags.Double("dt-s", &o.course.dt_s, "S", "s", "step between controls and fixes");
  flags.Double("wheelbase-m", &o.model.wheelbase_m, "M", "m", "bicycle-model wheelbase L");
  flags.Double("straight-m", &o.course.straight_m, "M", "m", "straight of each side of the rounded square");
  flags.Double("turn-radius-m", &o.course.turn_radius_m, "M", "m", "radius of its quarter-circle corners");
  flags.Double("speed-sigma-mps", &o.control_noise.speed_sigma_mps, "V", "m/s",
               "per-step speed error of the truth, and the filters' model of it");
  flags.Double("steering-sigma-rad", &o.control_noise.steering_sigma_rad, "R", "rad",
               "per-step steering error of the truth, and the filters' model of it");
  flags.Double("initial-position-sigma-m", &o.initial_position_sigma_m, "M", "m",
               "filters' prior std of x and y around the known start");
  flags.Double("initial-heading-sigma-rad", &o.initial_heading_sigma_rad, "R", "rad",
               "filters' prior std of the heading around the known start");
  flags.Double("kalman-sigma-m", &o.kalman_sigma_m, "M", "m",
               "measurement std sigma_R the Kalman filters and PF-Gauss assume; 0: the Gaussian "
               "component's sigma");
  flags.Double("huber-threshold", &o.huber_threshold, "C", "sigma_R", "Huber threshold c");
  flags.Double("student-dof", &o.student_dof, "NU", "", "degrees of freedom of EKF-t");
  flags.Double("resample-ess-fraction", &o.resample_ess_fraction, "F", "", "PFs resample when ESS < F * particles");
  flags.Double("divergence-error-m", &o.divergence_error_m, "M", "m",
               "a run counts as diverged when its final-lap mean error exceeds this");
  flags.Strings("filter", &o.filters, "NAME",
                "run only these filters, in this order; all when absent (" + FilterList() + ")");
  flags.Bool("quiet", &f.quiet, "no progress on stderr");
}

// Progress on stderr, one line per 10 % of the runs, once the experiment has taken more
// than a second (the default 100 runs take about 2.5 s; a short run prints nothing).
std::function<void(int)> Progress(int runs, bool quiet) {
  if (quiet) return {};
  const auto start = std::chrono::steady_clock::now();
  return [runs, start, last = 0](int done) mutable {
    const int decile = 10 * done / runs;
    if (decile == last) return;
    last = decile;
    if (std::chrono::steady_clock::now() - start < std::chrono::seconds(1)) return;
    std::fprintf(stderr, "%s: %d/%d runs\n", kPfVsEkf2d, done, runs);
  };
}

void PrintTable(const engine::experiments::PfVsEkf2dOptions& o, const engine::experiments::PfVsEkf2dResult& r,
                double wall_s) {
  std::printf("# %s: %d runs, seed %llu, %d steps per run (%d laps x %d steps of %g s), %d particles\n", kPfVsEkf2d,
              r.runs, static_cast<unsigned long long>(o.seed), r.steps_per_run, o.course.laps, r.steps_per_lap,
              o.course.dt_s, o.particles);
  std::printf("# seed's figures for reference: EKF 19.48 m (sd 12.54), PF 0.334 m (sd 0.217)\n");
  std::printf(
      "# std_m: std of per-step errors pooled over steps and runs; run_std_m: std of per-run"
      " mean errors;\n# divergences: runs whose final-lap mean error exceeds %g m\n",
      o.divergence_error_m);
  std::printf("%-10s %12s %8s %11s %9s %9s %11s %11s\n", "filter", "mean_error_m", "std_m", "divergences", "median_m",
              "run_std_m", "final_lap_m", "us_per_step");
  for (const auto& f : r.filters) {
    std::printf("%-10s %12.3f %8.3f %11d %9.3f %9.3f %11.3f %11.2f\n", f.name.c_str(), f.mean_error_m, f.step_std_m,
                f.divergences, f.median_error_m, f.run_std_m, f.final_lap_error_m, f.us_per_step);
  }
  std::printf("# wall time %.2f s\n", wall_s);
}

int RunPfVsEkf2dCommand(const std::vector<std::string>& args) {
  ExperimentFlags f;
  FlagSet flags(std::string("localizer-cli experiment ") + kPfVsEkf2d + " [flags]",
                "The seed's 2-D experiment: a car-like vehicle (bicycle model, known commands)\n"
                "drives a closed course (a rounded square, from (0, 0) heading 0); its position\n"
                "fixes carry per-axis noise that is Gaussian with probability e, else alpha-stable\n"
                "S1(alpha, beta, scale, location). A PF with the true mixture likelihood runs\n"
                "beside EKF, UKF and robust Kalman variants. Prints one row per filter:\n"
                "name, mean error (m), std (m), divergences, then median, per-run std, final-lap\n"
                "error and time per step. Errors replay bit for bit for a seed; times do not.");
  RegisterFlags(flags, f);
  if (auto exit_code = ParseFlagsOrExit(kCommand, flags, args)) return *exit_code;
  if (const Status valid = f.options.Validate(); !valid.ok()) {
    return UsageError(kCommand, valid.message());
  }
  const auto start = std::chrono::steady_clock::now();
  auto result = engine::experiments::RunPfVsEkf2d(f.options, Progress(f.options.runs, f.quiet));
  if (!result.ok()) return RuntimeError(kCommand, result.status());
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  PrintTable(f.options, *result, wall_s);
  return kExitOk;
}

std::string ExperimentUsage() {
  return std::string("usage: localizer-cli experiment NAME [flags]\n\n") +
         "Reproduces a reference experiment and prints its table. Experiments:\n"
         "  " +
         kPfVsEkf2d +
         "   particle filter vs EKF/UKF and robust variants, 2-D, alpha-stable noise\n"
         "  " +
         kFwl +
         "            fixed-point word length of a steady-state tracking filter (Tables 1, 2)\n"
         "  " +
         kTws +
         "            track-while-scan of N targets in clutter on a rotating radar\n\n"
         "'localizer-cli experiment NAME --help' lists its flags, defaults and units.\n";
}

}  // namespace

int RunExperiment(const std::vector<std::string>& args) {
  if (args.empty())
    return UsageError(kCommand, "name an experiment (" + std::string(kPfVsEkf2d) + ", " + kFwl + ", " + kTws + ")");
  const std::string& name = args.front();
  if (name == "--help" || name == "-h") {
    std::cout << ExperimentUsage();
    return kExitOk;
  }
  const std::vector<std::string> rest(args.begin() + 1, args.end());
  if (name == kFwl) return RunFwlExperiment(rest);
  if (name == kTws) return RunTwsExperiment(rest);
  if (name != kPfVsEkf2d) {
    return UsageError(kCommand,
                      "unknown experiment \"" + name + "\" (known: " + kPfVsEkf2d + ", " + kFwl + ", " + kTws + ")");
  }
  return RunPfVsEkf2dCommand(rest);
}

}  // namespace localizer::cli
