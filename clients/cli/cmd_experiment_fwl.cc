// localizer-cli experiment fwl: the seed's Tables 1 and 2, round-off of a b-bit fixed-point
// steady-state tracking filter, simulated and computed (engine/experiments/fwl_study.h holds
// the systems, the arithmetic and the definitions of the columns).
#include <cstdio>
#include <iostream>
#include <string>

#include "clients/cli/commands.h"
#include "clients/cli/experiment_commands.h"
#include "engine/experiments/fwl_study.h"

namespace localizer::cli {
namespace {

const char* const kCommand = "experiment fwl";

void PrintTable(const engine::experiments::FwlOptions& o, const engine::experiments::FwlResult& r) {
  const auto& s = r.system;
  std::printf("# fwl: system %s; %d runs, seed %llu, steps %d..%d averaged\n", s.name.c_str(), o.runs,
              static_cast<unsigned long long>(o.seed), o.first_step, o.last_step);
  std::printf("# T %.4f s, sigma_w %g %s, alpha %.4f, beta %.4f, scaling S = diag(%g, %g)\n", s.period_s,
              s.measurement_sigma, s.units.c_str(), r.alpha, r.beta, s.scale(0), s.scale(1));
  std::printf("# variances of the position output error in %s^2\n", s.units.c_str());
  const auto seed_figures = engine::experiments::SeedFwlFigures(o.system);
  const bool scaled = o.system == 2;
  std::printf("%4s %12s %12s", "bits", "simulated", "computed");
  if (scaled) std::printf(" %12s", "computed_unscaled");
  std::printf(" %9s %14s %14s\n", "overflows", "seed_measured", "seed_computed");
  for (const auto& row : r.rows) {
    std::printf("%4d %12.3e %12.3e", row.bits, row.simulated, row.computed_scaled);
    if (scaled) std::printf(" %17.3e", row.computed_unscaled);
    std::printf(" %9lld", static_cast<long long>(row.overflows));
    bool found = false;
    for (const auto& f : seed_figures) {
      if (f.bits != row.bits) continue;
      std::printf(" %14.2e %14.2e", f.measured, f.computed);
      found = true;
    }
    if (!found) std::printf(" %14s %14s", "-", "-");
    std::printf("\n");
  }
}

}  // namespace

int RunFwlExperiment(const std::vector<std::string>& args) {
  engine::experiments::FwlOptions o;
  FlagSet flags("localizer-cli experiment fwl [flags]",
                "The seed's fixed-point word-length study: a steady-state (alpha-beta) tracking\n"
                "filter in b-bit Q-format arithmetic, rounding after every multiplication, against\n"
                "the same filter in double precision. Prints one row per word length: bits, the\n"
                "simulated output-error variance, the variance computed from the round-off model\n"
                "(and, for system 2, the model applied as if the filter were unscaled), the\n"
                "saturation count and the seed's figures where the issue quotes them.");
  flags.Int("system", &o.system, "1|2", "",
            "1: normalised filter needing no scaling; 2: the seed's constant-velocity target, scaled");
  flags.Int("runs", &o.runs, "N", "", "Monte-Carlo runs per word length");
  flags.Uint64("seed", &o.seed, "S", "experiment seed: every run's measurement noise");
  flags.Int("min-bits", &o.min_bits, "B", "bits", "shortest word length");
  flags.Int("max-bits", &o.max_bits, "B", "bits", "longest word length");
  flags.Int("first-step", &o.first_step, "K", "", "first step averaged (the seed: 11)");
  flags.Int("last-step", &o.last_step, "K", "", "last step simulated and averaged (the seed: 30)");
  if (auto exit_code = ParseFlagsOrExit(kCommand, flags, args)) return *exit_code;
  if (const Status valid = o.Validate(); !valid.ok()) return UsageError(kCommand, valid.message());
  auto result = engine::experiments::RunFwlStudy(o);
  if (!result.ok()) return RuntimeError(kCommand, result.status());
  PrintTable(o, *result);
  return kExitOk;
}

}  // namespace localizer::cli
