// Simulates a named scenario and tracks it through one Session with the scenario's band:
// shared by the accuracy tests and tests/bench/accuracy_report.cc.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "engine/pipeline/session.h"
#include "engine/sim/evaluation.h"

namespace localizer::engine {

struct ScenarioRun {
  std::vector<Estimate> estimates;
  TrackScore score;  // estimates from 2 s on, against the simulator's truth
  AudioSessionConfig config;
  SimResult sim;  // the simulated recording and its truth
};

// The session config that tracks `scenario`: its array, sample rate and band. TrackScenario's
// `adjust`, when set, changes the config last.
inline AudioSessionConfig SessionConfigFor(const Scenario& scenario) {
  AudioSessionConfig config;
  config.sensors_m = scenario.sensors_m;
  config.sound_speed_mps = scenario.sound_speed_mps;
  config.sample_rate_hz = scenario.sim.sample_rate_hz;
  config.band_low_hz = scenario.sim.band_low_hz;
  config.band_high_hz = scenario.sim.band_high_hz;
  return config;
}

inline ScenarioRun TrackScenario(const std::string& name, uint64_t seed, Likelihood likelihood,
                                 BackendChoice backend = BackendChoice::kCpu, FilterKind filter = FilterKind::kPf,
                                 MotionModelKind motion_model = MotionModelKind::kCv,
                                 const std::function<void(AudioSessionConfig*)>& adjust = nullptr) {
  const Scenario scenario = *MakeScenario(name, seed);
  const ArrayGeometry array = *ArrayGeometry::Create(scenario.sensors_m, scenario.sound_speed_mps);
  SimResult sim = *Simulate(array, scenario.sim);
  AudioSessionConfig config = SessionConfigFor(scenario);
  config.tracker.particle.likelihood = likelihood;
  config.seed = seed;
  config.backend = backend;
  config.tracker.kind = filter;
  config.tracker.kalman.motion_model = motion_model;
  if (adjust) adjust(&config);
  auto session = std::move(*Session::Create(config));
  ScenarioRun run;
  (void)session->Process({1, sim.channel_count, sim.samples_per_channel, sim.samples.data()}, &run.estimates);
  run.score = ScoreTrack(array, sim, run.estimates, /*skip_s=*/2.0);
  run.config = config;
  run.sim = std::move(sim);
  return run;
}

}  // namespace localizer::engine
