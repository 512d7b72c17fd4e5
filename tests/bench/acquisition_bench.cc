// Cost of one acquisition frame (engine/acquisition): the volume search with its presence
// test, and the presence test about a track, on frames of the named scenes (4 and 8
// sensors). Run: build/tests/bench/acquisition_bench --benchmark_repetitions=5
//      --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "engine/acquisition/acquisition.h"
#include "engine/pipeline/session.h"
#include "engine/sim/simulator.h"
#include "engine/tdoa/gcc_phat.h"

namespace localizer::engine {
namespace {

struct Frame {
  ArrayGeometry array;
  Measurement measurement;
  Vec3 truth_m;
};

// The named scene's frame 10 (4096 samples), measured as a session would (no band hint),
// with the pairs without the reference when the array has at most cross_pairs_max_sensors
// sensors (a session's search asks for them: GccOptions::cross_pairs_max_sensors).
Frame MakeFrame(const std::string& name, int cross_pairs_max_sensors = 0) {
  Scenario scenario = *MakeScenario(name, 1);
  scenario.sim.duration_s = 3.0;
  const ArrayGeometry array = *ArrayGeometry::Create(scenario.sensors_m, scenario.sound_speed_mps);
  const SimResult sim = *Simulate(array, scenario.sim);
  GccOptions gcc;
  gcc.sample_rate_hz = sim.sample_rate_hz;
  gcc.keep_gcc = true;
  gcc.cross_pairs_max_sensors = cross_pairs_max_sensors;
  auto estimator = *GccPhatEstimator::Create(array, gcc);
  std::vector<float> frame(static_cast<size_t>(sim.channel_count * 4096));
  const int64_t start = 10 * 2048;
  for (int c = 0; c < sim.channel_count; ++c) {
    std::copy_n(sim.samples.begin() + c * sim.samples_per_channel + start, 4096, frame.begin() + c * 4096);
  }
  Frame out{array, {}, Vec3::Zero()};
  const double t_s = (start + 2047.5) / sim.sample_rate_hz;
  (void)estimator->Estimate(frame.data(), 4096, t_s, &out.measurement);
  (void)estimator->MeasureCrossPairs(&out.measurement);
  out.truth_m = sim.TruthAt(t_s).position_m;
  return out;
}

const char* const kScenes[] = {"tetra-water", "tetra-air", "turn-multipath"};

void BM_Search(benchmark::State& state) {
  // Second argument: cross_pairs_max_sensors (4, a session's default: the 4-sensor scenes
  // search six pairs instead of three; 0: the reference pairs only). Third: 1 with
  // AcquisitionOptions::earlier_arrivals (the default), 0 without.
  const Frame f = MakeFrame(kScenes[state.range(0)], static_cast<int>(state.range(1)));
  AcquisitionOptions options;
  options.earlier_arrivals = state.range(2) != 0;
  auto acquisition = *Acquisition::Create(f.array, options);
  size_t modes = 0;
  for (auto _ : state) {
    const AcquisitionResult r = acquisition.Search(f.measurement);
    modes = r.modes.size();
    benchmark::DoNotOptimize(r.presence.statistic);
  }
  state.SetLabel(std::string(kScenes[state.range(0)]) + (f.measurement.cross_pairs.empty() ? "" : " cross-pairs") +
                 (options.earlier_arrivals ? " earlier-arrivals" : ""));
  state.counters["modes"] = static_cast<double>(modes);
}
BENCHMARK(BM_Search)->ArgsProduct({{0, 1, 2}, {0, 4, 8}, {0, 1}})->Unit(benchmark::kMicrosecond);

void BM_PresenceAroundTrack(benchmark::State& state) {
  const Frame f = MakeFrame(kScenes[state.range(0)]);
  auto acquisition = *Acquisition::Create(f.array, AcquisitionOptions{});
  for (auto _ : state) {
    benchmark::DoNotOptimize(acquisition.Around(f.measurement, f.truth_m, 0.01 * Mat3::Identity()).statistic);
  }
  state.SetLabel(kScenes[state.range(0)]);
}
BENCHMARK(BM_PresenceAroundTrack)->DenseRange(0, 2)->Unit(benchmark::kMicrosecond);

// A session's audit check every 8 tracked frames (session_impl.h, EchoedChannelAtTrack): the
// field about the track rebuilt with every pair, then each channel's earlier arrival sought.
void BM_EarlierArrivalAtTrack(benchmark::State& state) {
  const Frame f = MakeFrame(kScenes[state.range(0)], 8);
  auto acquisition = *Acquisition::Create(f.array, AcquisitionOptions{});
  std::vector<double> lags;
  for (auto _ : state) {
    (void)acquisition.Around(f.measurement, f.truth_m, 0.01 * Mat3::Identity());
    benchmark::DoNotOptimize(acquisition.EarlierArrival(f.truth_m, &lags));
  }
  state.SetLabel(kScenes[state.range(0)]);
}
BENCHMARK(BM_EarlierArrivalAtTrack)->DenseRange(0, 2)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace localizer::engine

BENCHMARK_MAIN();
