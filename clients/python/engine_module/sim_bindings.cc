// The simulator (engine/sim): a named scenario or a scene drawn at random from a seed,
// rendered into (samples, channels) float32 plus the truth, so that a Python user can
// simulate -> Session.process as localizer-cli simulate -> track does.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <optional>
#include <string>

#include "clients/python/engine_module/bindings.h"
#include "clients/python/engine_module/errors.h"
#include "clients/python/engine_module/numpy_convert.h"
#include "engine/array/array_geometry.h"
#include "engine/sim/random_scene.h"
#include "engine/sim/simulator.h"

namespace localizer::python {

namespace {

py::array TruthToArray(const std::vector<engine::TruthRow>& truth) {
  RecordWriter out(RecordDtype({{"t_s", "<f8", {}},
                                {"x_m", "<f8", {}},
                                {"y_m", "<f8", {}},
                                {"z_m", "<f8", {}},
                                {"vx_mps", "<f8", {}},
                                {"vy_mps", "<f8", {}},
                                {"vz_mps", "<f8", {}}}),
                   truth.size());
  const size_t t_at = out.Offset("t_s"), position_at = out.Offset("x_m"), velocity_at = out.Offset("vx_mps");
  for (size_t row = 0; row < truth.size(); ++row) {
    out.Set<double>(row, t_at, truth[row].t_s);
    out.SetMany(row, position_at, truth[row].position_m.data(), 3);  // x_m, y_m, z_m are adjacent
    out.SetMany(row, velocity_at, truth[row].velocity_mps.data(), 3);
  }
  return out.array();
}

// Renders `scenario` (GIL released) and returns the scene as a dict (see the stub).
py::dict Render(const engine::Scenario& scenario) {
  const engine::ArrayGeometry array =
      ValueOrThrow(engine::ArrayGeometry::Create(scenario.sensors_m, scenario.sound_speed_mps));
  StatusOr<engine::SimResult> result = Status(StatusCode::kInternal, "not simulated");
  {
    py::gil_scoped_release release;
    result = engine::Simulate(array, scenario.sim);
  }
  ThrowIfError(result.status());
  // (samples, channels) in Fortran order is the engine's channel-major memory as it is:
  // Session.process takes it without a copy.
  py::array_t<float, py::array::f_style> samples(
      {static_cast<py::ssize_t>(result->samples_per_channel), static_cast<py::ssize_t>(result->channel_count)});
  std::copy(result->samples.begin(), result->samples.end(), samples.mutable_data());
  py::array_t<double> sensors({static_cast<py::ssize_t>(scenario.sensors_m.size()), py::ssize_t{3}});
  for (size_t i = 0; i < scenario.sensors_m.size(); ++i)
    for (int a = 0; a < 3; ++a) sensors.mutable_at(static_cast<py::ssize_t>(i), a) = scenario.sensors_m[i][a];
  py::dict scene;
  scene["name"] = scenario.name;
  scene["description"] = scenario.description;
  scene["samples"] = samples;
  scene["sample_rate_hz"] = result->sample_rate_hz;
  scene["sensors_m"] = sensors;
  scene["sound_speed_mps"] = scenario.sound_speed_mps;
  scene["reference_sensor"] = array.reference_sensor();
  scene["band_hz"] = py::make_tuple(scenario.sim.band_low_hz, scenario.sim.band_high_hz);
  scene["snr_db"] = scenario.sim.snr_db;
  scene["seed"] = scenario.sim.seed;
  scene["truth"] = TruthToArray(result->truth);
  return scene;
}

py::dict SimulateScenario(const std::string& name, uint64_t seed, std::optional<double> duration_s,
                          std::optional<double> snr_db) {
  engine::Scenario scenario = ValueOrThrow(engine::MakeScenario(name, seed));
  if (duration_s) scenario.sim.duration_s = *duration_s;
  if (snr_db) scenario.sim.snr_db = *snr_db;
  return Render(scenario);
}

py::dict SimulateRandomScene(uint64_t seed, double duration_s, std::optional<std::string> scene_class) {
  engine::RandomSceneOptions options;
  options.duration_s = duration_s;
  if (scene_class) options.scene_class = ValueOrThrow(engine::ParseSceneClass(*scene_class));
  const engine::RandomScene drawn = ValueOrThrow(engine::DrawRandomScene(seed, options));
  py::dict scene = Render(drawn.scenario);
  scene["scene_class"] = engine::SceneClassName(drawn.scene_class);
  scene["medium"] = drawn.medium;
  scene["aperture_m"] = drawn.aperture_m;
  scene["start_range_m"] = drawn.start_range_m;
  return scene;
}

}  // namespace

void RegisterSimulator(py::module_& m) {
  m.def("scenario_names", &engine::ScenarioNames, "The named scenarios, in the engine's order.");
  m.def("simulate_scenario", &SimulateScenario, py::arg("name"), py::arg("seed") = 1, py::kw_only(),
        py::arg("duration_s") = py::none(), py::arg("snr_db") = py::none(),
        "A named scenario (engine::MakeScenario) rendered: dict with samples (samples, channels) float32, "
        "sample_rate_hz, sensors_m, sound_speed_mps, band_hz, truth (structured array), ...");
  m.def("simulate_random_scene", &SimulateRandomScene, py::arg("seed"), py::kw_only(),
        py::arg("duration_s") = engine::RandomSceneOptions{}.duration_s, py::arg("scene_class") = py::none(),
        "A scene drawn at random from the seed (engine::DrawRandomScene) rendered, as simulate_scenario, "
        "plus scene_class, medium, aperture_m, start_range_m.");
}

}  // namespace localizer::python
