// How the pipeline's cost grows (issue 20's table): CPU milliseconds per audio-second of one
// Session (framing, GCC-PHAT, particle filter) as one parameter moves away from the reference
// configuration (4 channels, 44.1 kHz, 4096-sample frames, 50 % hop, 4096 particles, peak
// likelihood), with the stage split per frame so that the dominant term shows.
//   particles:  256 ... 65536
//   sensors:    4, 8, 16, 32 (reference pairs grow as sensors - 1; the GCC's FFTs as sensors);
//               and 4, 6, 8 with every pair measured (BM_CostWithEveryPair)
//   frame:      256 ... 8192 samples (hop = frame / 2, so frames per second grow as 1 / frame)
//   rate:       8 ... 96 kHz (frame fixed at 4096: frames per second grow with the rate)
// The sensors sit on a Fibonacci lattice over a 0.25 m-radius sphere (volumetric for every
// count); the source is the tetra-air talker (engine/sim scenarios), 6 s of audio.
// Run: build/tests/bench/cost_sweep_bench --benchmark_repetitions=3
//      --benchmark_report_aggregates_only=true
// The service's growth with sessions is tests/bench/service_capacity.py's (BENCHMARKS.md).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>

#include "engine/pipeline/session.h"
#include "engine/sim/simulator.h"
#include "tests/bench/session_blocks.h"

namespace localizer::engine {
namespace {

struct Point {
  int particles = 4096;
  int sensors = 4;
  int frame_samples = 4096;
  double sample_rate_hz = 44100.0;
  int cross_pairs_max_sensors = -1;  // < 0: the session's default
};

std::vector<Vec3> FibonacciSphere(int n, double radius_m) {
  std::vector<Vec3> points;
  const double golden_rad = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / n;
    const double r = std::sqrt(1.0 - z * z);
    points.push_back(radius_m * Vec3(r * std::cos(golden_rad * i), r * std::sin(golden_rad * i), z));
  }
  return points;
}

// The scene's audio per (sensors, rate), simulated once.
const std::pair<Scenario, SimResult>& Audio(int sensors, double sample_rate_hz) {
  static std::map<std::pair<int, double>, std::pair<Scenario, SimResult>> cache;
  const auto key = std::make_pair(sensors, sample_rate_hz);
  auto it = cache.find(key);
  if (it == cache.end()) {
    Scenario s = *MakeScenario("tetra-air", 1);
    s.sensors_m = FibonacciSphere(sensors, 0.25);
    s.sim.sample_rate_hz = sample_rate_hz;
    s.sim.duration_s = 6.0;
    s.sim.band_high_hz = std::min(s.sim.band_high_hz, 0.45 * sample_rate_hz);  // 8 kHz: below Nyquist
    SimResult sim = *Simulate(*ArrayGeometry::Create(s.sensors_m, s.sound_speed_mps), s.sim);
    it = cache.emplace(key, std::make_pair(std::move(s), std::move(sim))).first;
  }
  return it->second;
}

void Run(benchmark::State& state, const Point& p) {
  const auto& [scenario, sim] = Audio(p.sensors, p.sample_rate_hz);
  AudioSessionConfig config;
  config.sensors_m = scenario.sensors_m;
  config.sound_speed_mps = scenario.sound_speed_mps;
  config.sample_rate_hz = sim.sample_rate_hz;
  config.frame_samples = p.frame_samples;
  config.hop_samples = p.frame_samples / 2;
  config.tracker.particle.particles = p.particles;
  config.tracker.particle.likelihood = Likelihood::kPeak;
  if (p.cross_pairs_max_sensors >= 0) config.cross_pairs_max_sensors = p.cross_pairs_max_sensors;
  // 0.1 s blocks, as a streaming client sends them.
  const int64_t block = static_cast<int64_t>(std::lround(0.1 * sim.sample_rate_hz));
  const std::vector<std::vector<float>> blocks = bench::SplitIntoBlocks(sim, block);
  const double audio_s = static_cast<double>(blocks.size() * block) / sim.sample_rate_hz;
  std::vector<Estimate> out;
  bench::StageTotals totals;
  for (auto _ : state) {
    state.PauseTiming();  // set-up (FFT plans, allocation) is not per-audio work
    auto created = Session::Create(config);
    if (!created.ok()) {
      state.SkipWithError(created.status().message().c_str());
      return;
    }
    auto session = std::move(*created);
    state.ResumeTiming();
    bench::RunBlocks(*session, blocks, sim.channel_count, block, &out, &totals);
  }
  const double runs = static_cast<double>(state.iterations());
  state.counters["ms_per_audio_s"] =
      benchmark::Counter(runs * audio_s * 1e-3, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["frames_per_audio_s"] = static_cast<double>(totals.frames) / (runs * audio_s);
  state.counters["tdoa_us_per_frame"] = 1e6 * totals.tdoa_s / static_cast<double>(totals.frames);
  state.counters["filter_us_per_frame"] = 1e6 * totals.filter_s / static_cast<double>(totals.frames);
}

void BM_CostVsParticles(benchmark::State& state) {
  Point p;
  p.particles = static_cast<int>(state.range(0));
  Run(state, p);
}
BENCHMARK(BM_CostVsParticles)->RangeMultiplier(4)->Range(256, 65536)->Unit(benchmark::kMillisecond);

void BM_CostVsSensors(benchmark::State& state) {
  Point p;
  p.sensors = static_cast<int>(state.range(0));
  Run(state, p);
}
BENCHMARK(BM_CostVsSensors)->Arg(4)->Arg(8)->Arg(16)->Arg(32)->Unit(benchmark::kMillisecond);

// Every pair measured (cross_pairs_max_sensors = sensors): the pairs without the reference on
// every tracked frame (pair_closure.h) and in every search, against BM_CostVsSensors' default
// (4: larger arrays measure only their reference pairs).
void BM_CostWithEveryPair(benchmark::State& state) {
  Point p;
  p.sensors = static_cast<int>(state.range(0));
  p.cross_pairs_max_sensors = p.sensors;
  Run(state, p);
}
BENCHMARK(BM_CostWithEveryPair)->Arg(4)->Arg(6)->Arg(8)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CostVsSensors)->Arg(6)->Unit(benchmark::kMillisecond);

void BM_CostVsFrame(benchmark::State& state) {
  Point p;
  p.frame_samples = static_cast<int>(state.range(0));
  Run(state, p);
}
BENCHMARK(BM_CostVsFrame)->RangeMultiplier(2)->Range(256, 8192)->Unit(benchmark::kMillisecond);

void BM_CostVsRate(benchmark::State& state) {
  Point p;
  p.sample_rate_hz = static_cast<double>(state.range(0));
  Run(state, p);
}
BENCHMARK(BM_CostVsRate)->Arg(8000)->Arg(16000)->Arg(44100)->Arg(96000)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace localizer::engine

BENCHMARK_MAIN();
