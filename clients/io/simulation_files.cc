#include "clients/io/simulation_files.h"

#include <cmath>
#include <filesystem>

#include "clients/io/array_json.h"
#include "clients/io/csv_io.h"
#include "clients/io/wav_io.h"
#include "engine/array/array_geometry.h"

namespace localizer::io {

StatusOr<SimulationRun> SimulateScenario(const std::string& name, uint64_t seed, std::optional<double> duration_s) {
  auto scenario = engine::MakeScenario(name, seed);
  if (!scenario.ok()) return scenario.status();
  if (duration_s) {
    if (!(*duration_s > 0.0 && std::isfinite(*duration_s))) {
      return InvalidArgument("duration " + std::to_string(*duration_s) + " s must be > 0");
    }
    scenario->sim.duration_s = *duration_s;
  }
  SimulationRun run;
  auto geometry = engine::ArrayGeometry::Create(scenario->sensors_m, scenario->sound_speed_mps, run.reference_sensor);
  if (!geometry.ok()) return geometry.status();
  auto result = engine::Simulate(*geometry, scenario->sim);
  if (!result.ok()) return result.status();
  run.scenario = std::move(*scenario);
  run.result = std::move(*result);
  return run;
}

StatusOr<SimulationFiles> WriteSimulationFiles(const std::string& dir, const SimulationRun& run) {
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (error) return InvalidArgument(dir + ": cannot create directory: " + error.message());
  const std::filesystem::path base(dir);
  SimulationFiles files{(base / "signals.wav").string(), (base / "array.json").string(), (base / "truth.csv").string()};
  const engine::SimResult& r = run.result;
  LOCALIZER_RETURN_IF_ERROR(
      WriteWavFloat(files.wav_path, r.sample_rate_hz, r.channel_count, r.samples_per_channel, r.samples.data()));
  ArrayFile array;
  array.sensors_m = run.scenario.sensors_m;
  array.sound_speed_mps = run.scenario.sound_speed_mps;
  array.sample_rate_hz = r.sample_rate_hz;
  array.reference_sensor = run.reference_sensor;
  array.band_hz = std::make_pair(run.scenario.sim.band_low_hz, run.scenario.sim.band_high_hz);
  LOCALIZER_RETURN_IF_ERROR(WriteArrayJson(files.array_path, array));
  LOCALIZER_RETURN_IF_ERROR(WriteTruthCsv(files.truth_path, r.truth));
  return files;
}

}  // namespace localizer::io
