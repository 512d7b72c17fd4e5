// A simulated scenario on disk: the body of `localizer-cli simulate`, kept in the io library
// so tests run the code the command runs.
//
// DIR/signals.wav  float32, channel k = sensor k, at the scenario's sample rate
// DIR/array.json   sensors, sound speed, sample_rate_hz, reference_sensor (the one the
//                  truth times refer to)
// DIR/truth.csv    engine::TruthRow per truth step (see csv_io.h)
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "engine/core/status.h"
#include "engine/sim/simulator.h"

namespace localizer::io {

struct SimulationRun {
  engine::Scenario scenario;  // after the overrides
  engine::SimResult result;
  int reference_sensor = 0;  // of the geometry the simulator used for truth times
};

// engine::MakeScenario(name, seed), with the duration overridden when given (> 0).
StatusOr<SimulationRun> SimulateScenario(const std::string& name, uint64_t seed, std::optional<double> duration_s);

struct SimulationFiles {
  std::string wav_path;
  std::string array_path;
  std::string truth_path;
};

// Creates `dir` (and parents) if needed and writes the three files.
StatusOr<SimulationFiles> WriteSimulationFiles(const std::string& dir, const SimulationRun& run);

}  // namespace localizer::io
