// Whole pipeline (framing, GCC-PHAT, particle filter) on one core: CPU milliseconds per
// second of audio for 4 channels at 44.1 kHz, 4096-sample frames, 50 % hop, 4096 particles.
// The engine issue's goal is <= 2.5 ms, issue 20's <= 2.0; the seed's Jetson TX1 took 18.24
// (GPU) / 56.95 (CPU). BM_PipelineInterleavedSessions runs several sessions block by block in
// turn, as the server's workers do, to show what sharing the caches costs.
// Run: build/tests/bench/pipeline_bench --benchmark_repetitions=5
//      --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <memory>
#include <string>

#include "engine/pipeline/range_observability.h"
#include "engine/pipeline/session.h"
#include "engine/sim/simulator.h"
#include "tests/bench/session_blocks.h"

namespace localizer::engine {
namespace {

const SimResult& Audio(double fs, Scenario* scenario_out) {
  static Scenario scenario = [] {
    Scenario s = *MakeScenario("tetra-air", 1);
    s.sim.sample_rate_hz = 44100.0;
    s.sim.duration_s = 6.0;
    return s;
  }();
  static const SimResult sim =
      *Simulate(*ArrayGeometry::Create(scenario.sensors_m, scenario.sound_speed_mps), scenario.sim);
  (void)fs;
  *scenario_out = scenario;
  return sim;
}

// The benchmarks' session: the scenario's array, frames of 4096 with hop 2048.
AudioSessionConfig BenchConfig(const Scenario& scenario, const SimResult& sim, int particles, Likelihood likelihood) {
  AudioSessionConfig config;
  config.sensors_m = scenario.sensors_m;
  config.sound_speed_mps = scenario.sound_speed_mps;
  config.sample_rate_hz = sim.sample_rate_hz;
  config.frame_samples = 4096;
  config.hop_samples = 2048;
  config.tracker.particle.particles = particles;
  config.tracker.particle.likelihood = likelihood;
  return config;
}

// Runs `config` over the benchmark's audio in 0.1-s blocks, as a streaming client would send
// them, and sets the counters: CPU ms per audio-second, TDOA and filter stage us per frame.
void MeasurePerAudioSecond(benchmark::State& state, const SimResult& sim, const AudioSessionConfig& config) {
  const int64_t block = 4410;
  const std::vector<std::vector<float>> blocks = bench::SplitIntoBlocks(sim, block);
  const double audio_s = static_cast<double>(blocks.size() * block) / sim.sample_rate_hz;
  std::vector<Estimate> out;
  bench::StageTotals totals;
  for (auto _ : state) {
    state.PauseTiming();  // session set-up (FFT planning, allocation) is not per-audio work
    auto session = std::move(*Session::Create(config));
    state.ResumeTiming();
    bench::RunBlocks(*session, blocks, sim.channel_count, block, &out, &totals);
  }
  const double runs = static_cast<double>(state.iterations());
  state.counters["ms_per_audio_s"] =
      benchmark::Counter(runs * audio_s * 1e-3, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["tdoa_us_per_frame"] = 1e6 * totals.tdoa_s / static_cast<double>(totals.frames);
  state.counters["filter_us_per_frame"] = 1e6 * totals.filter_s / static_cast<double>(totals.frames);
}

void BM_PipelinePerAudioSecond(benchmark::State& state) {
  Scenario scenario;
  const SimResult& sim = Audio(44100.0, &scenario);
  AudioSessionConfig config = BenchConfig(scenario, sim, static_cast<int>(state.range(0)),
                                          state.range(1) == 0 ? Likelihood::kPeak : Likelihood::kGcc);
  // Third argument 1: the default motion (acceleration levels, turn rates and speed changes:
  // ACCURACY.md, "Nineteenth pass"); 0: one std, the GPU filter's (the default before it).
  if (state.range(2) == 0) config.tracker.particle.SetSingleMotion();
  // Fourth: cross_pairs_max_sensors (4 or more, the default 8: this 4-sensor array also measures its
  // three pairs without the reference; 0: off, the cost before them).
  config.cross_pairs_max_sensors = static_cast<int>(state.range(3));
  // Fifth: pair_closure (1, the default: with the cross pairs on, every tracked frame measures
  // them and checks its reference pairs against them; 0: only searching frames measure them).
  config.pair_closure = state.range(4) == 1;
  // Sixth: pair_fusion (1, the default: tracked frames fold the cross pairs into the reference
  // pairs' delays, pair_fusion.h; 0: the cost before it).
  config.pair_fusion = state.range(5) == 1;
  MeasurePerAudioSecond(state, sim, config);
  state.SetLabel(std::string(LikelihoodName(config.tracker.particle.likelihood)) +
                 (config.tracker.particle.single_motion() ? " one-std" : " levels+turns+speed") +
                 (config.cross_pairs_max_sensors >= 4 ? " cross-pairs" : "") +
                 (config.cross_pairs_max_sensors >= 4 && config.pair_closure ? " closure" : "") +
                 (config.cross_pairs_max_sensors >= 4 && config.pair_fusion ? " fusion" : ""));
}
BENCHMARK(BM_PipelinePerAudioSecond)
    ->ArgsProduct({{4096}, {0, 1}, {0, 1}, {0, 4}, {0, 1}, {0, 1}})
    ->Unit(benchmark::kMillisecond);

// The default session (/4096/0/1/4/1/1 above) with the particle filter's motion blur on (1)
// and off (0, the default): what widening each particle's pairs by its own delay rates costs
// (ParticleFilterOptions::motion_blur).
void BM_PipelineMotionBlur(benchmark::State& state) {
  Scenario scenario;
  const SimResult& sim = Audio(44100.0, &scenario);
  AudioSessionConfig config = BenchConfig(scenario, sim, 4096, Likelihood::kPeak);
  config.tracker.particle.motion_blur = static_cast<double>(state.range(0));
  MeasurePerAudioSecond(state, sim, config);
}
BENCHMARK(BM_PipelineMotionBlur)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond);

// Several sessions fed in turn, one 4096-sample block each, as the server's workers take
// them: each block finds its session's state (particles, filter scratch, transform buffers)
// where the other sessions' blocks left the caches. CPU per audio-second per session, to set
// against BM_PipelinePerAudioSecond (one session, its state always warm).
void BM_PipelineInterleavedSessions(benchmark::State& state) {
  const int sessions = static_cast<int>(state.range(0));
  Scenario scenario;
  const SimResult& sim = Audio(44100.0, &scenario);
  const AudioSessionConfig config = BenchConfig(scenario, sim, 4096, Likelihood::kPeak);
  const int64_t block = 4096;
  const std::vector<std::vector<float>> blocks = bench::SplitIntoBlocks(sim, block);
  const double audio_s = static_cast<double>(blocks.size() * block) / sim.sample_rate_hz;
  std::vector<Estimate> out;
  bench::StageTotals totals;
  for (auto _ : state) {
    state.PauseTiming();
    std::vector<std::unique_ptr<Session>> live;
    for (int k = 0; k < sessions; ++k) live.push_back(std::move(*Session::Create(config)));
    state.ResumeTiming();
    for (size_t b = 0; b < blocks.size(); ++b) {
      for (auto& session : live) {
        out.clear();
        (void)session->Process({b + 1, sim.channel_count, block, blocks[b].data()}, &out);
        for (const Estimate& e : out) {
          totals.tdoa_s += e.timings.tdoa_s;
          totals.filter_s += e.timings.filter_s;
        }
        totals.frames += out.size();
      }
    }
    state.PauseTiming();
    live.clear();
    state.ResumeTiming();
  }
  const double runs = static_cast<double>(state.iterations()) * sessions;
  state.counters["ms_per_audio_s"] =
      benchmark::Counter(runs * audio_s * 1e-3, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["tdoa_us_per_frame"] = 1e6 * totals.tdoa_s / static_cast<double>(totals.frames);
  state.counters["filter_us_per_frame"] = 1e6 * totals.filter_s / static_cast<double>(totals.frames);
}
BENCHMARK(BM_PipelineInterleavedSessions)->Arg(1)->Arg(8)->Arg(32)->Arg(128)->Unit(benchmark::kMillisecond);

// The far-field judgement a position session adds to every frame (Estimate::far_field):
// the pair sigmas' running median and the frame's range bound at the estimate, on the same
// array; compare with the pipeline's per-frame time (its ms_per_audio_s / frames per s).
void BM_FarFieldJudgementPerFrame(benchmark::State& state) {
  Scenario scenario;
  (void)Audio(44100.0, &scenario);
  const ArrayGeometry array = *ArrayGeometry::Create(scenario.sensors_m, scenario.sound_speed_mps);
  Measurement m;
  m.pairs.resize(static_cast<size_t>(array.pair_count()));
  for (size_t p = 0; p < m.pairs.size(); ++p) {
    m.pairs[p].peak_value = 0.5;
    m.pairs[p].delay_sigma_s = 2e-6 * static_cast<double>(p + 1);
  }
  PairSigmaHistory history;
  const Vec3 at = scenario.sim.trajectory.position_m;
  for (auto _ : state) {
    history.Add(m, 3e-6);
    benchmark::DoNotOptimize(JudgeRange(array, at, history.Median()));
  }
}
BENCHMARK(BM_FarFieldJudgementPerFrame)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace localizer::engine

BENCHMARK_MAIN();
