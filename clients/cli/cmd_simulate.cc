// localizer-cli simulate: a named scenario to signals.wav, array.json and truth.csv.
#include <algorithm>
#include <cstdio>
#include <iostream>

#include "clients/cli/commands.h"
#include "clients/io/simulation_files.h"
#include "engine/sim/simulator.h"

namespace localizer::cli {

namespace {

int ListScenarios(const std::string& command) {
  for (const std::string& name : engine::ScenarioNames()) {
    auto scenario = engine::MakeScenario(name);
    if (!scenario.ok()) return RuntimeError(command, scenario.status());
    std::string padded = name;
    padded.resize(std::max<size_t>(padded.size() + 2, 18), ' ');
    std::cout << padded << scenario->description << "\n";
  }
  return kExitOk;
}

bool IsScenario(const std::string& name) {
  const std::vector<std::string> names = engine::ScenarioNames();
  return std::find(names.begin(), names.end(), name) != names.end();
}

}  // namespace

int RunSimulate(const std::vector<std::string>& args) {
  const std::string command = "simulate";
  std::string scenario_name;
  std::string out_dir;
  uint64_t seed = 1;
  std::optional<double> duration_s;
  bool list = false;
  FlagSet flags("localizer-cli simulate --scenario NAME --out DIR [flags] | --list",
                "Simulates a named scenario (engine/sim) and writes DIR/signals.wav (float32,\n"
                "channel k = sensor k), DIR/array.json (with sample_rate_hz) and DIR/truth.csv.");
  flags.String("scenario", &scenario_name, "NAME", "scenario to simulate (see --list)");
  flags.String("out", &out_dir, "DIR", "output directory, created if missing");
  flags.Uint64("seed", &seed, "S", "random seed: source signal, noise, jitter");
  flags.OptionalDouble("duration", &duration_s, "S", "the scenario's own",
                       "seconds of recording to simulate");
  flags.Bool("list", &list, "print the scenario names and descriptions, then exit");
  if (auto exit_code = ParseFlagsOrExit(command, flags, args)) return *exit_code;
  if (list) return ListScenarios(command);
  if (scenario_name.empty()) return UsageError(command, "missing required flag --scenario");
  if (out_dir.empty()) return UsageError(command, "missing required flag --out");
  if (duration_s && *duration_s <= 0.0) return UsageError(command, "--duration must be > 0");

  if (!IsScenario(scenario_name)) {
    return UsageError(command, "unknown scenario \"" + scenario_name + "\" (see --list)");
  }

  auto run = io::SimulateScenario(scenario_name, seed, duration_s);
  if (!run.ok()) return RuntimeError(command, run.status());
  auto files = io::WriteSimulationFiles(out_dir, *run);
  if (!files.ok()) return RuntimeError(command, files.status());
  const engine::SimResult& r = run->result;
  std::printf(
      "simulated %s: %d channels, %.3f s at %g Hz, seed %llu -> %s (signals.wav, "
      "array.json, truth.csv)\n",
      scenario_name.c_str(), r.channel_count,
      static_cast<double>(r.samples_per_channel) / r.sample_rate_hz, r.sample_rate_hz,
      static_cast<unsigned long long>(seed), out_dir.c_str());
  return kExitOk;
}

}  // namespace localizer::cli
