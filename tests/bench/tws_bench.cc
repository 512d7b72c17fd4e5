// Track-while-scan: latency of one scan (predict, convert, gate, cluster, assign, update,
// manage, initiate) with 8, 100 and 1000 targets in clutter, and track updates per second.
//
// Scene: the seed's rotating radar (33 rpm, 83.3 km unambiguous range), targets placed at
// random 5 .. 66 km out (engine/sim/radar_scan.h RandomTargets), P_D 0.9, clutter
// 1e-9 /m^2 (~22 false plots per scan) or the heavier 1e-8 (~220). Scans are simulated
// before timing; each timed iteration is one Tracker::Process on a tracker that has
// already seen 10 scans (its tracks confirmed). A track update is one track's cycle in one
// scan (ScanSummary::track_updates).
//   ./tests/bench/tws_bench --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <memory>
#include <vector>

#include "engine/sim/radar_scan.h"
#include "engine/tws/tws_tracker.h"

namespace localizer::engine::tws {
namespace {

constexpr int kWarmScans = 10;
constexpr int kScans = 60;

std::vector<Scan> SimulatedScans(int targets, double clutter) {
  RadarScanOptions radar;
  radar.clutter_density_per_m2 = clutter;
  radar.seed = 7;
  auto sim = RadarScanSimulator::Create(radar, RandomTargets(targets, 5000.0, 0.8 * radar.OuterRangeM(), 1000.0, 7));
  std::vector<Scan> scans;
  for (int k = 0; k < kScans; ++k) scans.push_back(sim->Frame(k).scan);
  return scans;
}

std::unique_ptr<TwsTracker> WarmTracker(const std::vector<Scan>& scans, FilterForm form) {
  TwsOptions options;
  options.filter = form;
  auto tracker = std::move(TwsTracker::Create(options).value());
  for (int k = 0; k < kWarmScans; ++k) (void)tracker->Process(scans[k]);
  return tracker;
}

void BM_TwsScan(benchmark::State& state) {
  const int targets = static_cast<int>(state.range(0));
  const double clutter = state.range(1) == 0 ? 1e-9 : 1e-8;
  const FilterForm form = state.range(2) == 0 ? FilterForm::kKalman : FilterForm::kSteadyState;
  const std::vector<Scan> scans = SimulatedScans(targets, clutter);
  std::unique_ptr<TwsTracker> tracker = WarmTracker(scans, form);
  int k = kWarmScans;
  int64_t updates = 0, plots = 0, confirmed = 0, scans_done = 0;
  ScanSummary summary;
  for (auto _ : state) {
    if (k == kScans) {  // out of scans: start again with a fresh warm tracker, untimed
      state.PauseTiming();
      tracker = WarmTracker(scans, form);
      k = kWarmScans;
      state.ResumeTiming();
    }
    benchmark::DoNotOptimize(tracker->Process(scans[k++], &summary));
    updates += summary.track_updates;
    plots += summary.plots;
    confirmed += summary.confirmed;
    ++scans_done;
  }
  state.counters["track_updates_per_s"] = benchmark::Counter(static_cast<double>(updates), benchmark::Counter::kIsRate);
  state.counters["tracks_per_scan"] = static_cast<double>(updates) / static_cast<double>(scans_done);
  state.counters["plots_per_scan"] = static_cast<double>(plots) / static_cast<double>(scans_done);
  state.counters["confirmed"] = static_cast<double>(confirmed) / static_cast<double>(scans_done);
}

// (targets, clutter: 0 light / 1 heavy, filter: 0 Kalman / 1 steady-state)
BENCHMARK(BM_TwsScan)
    ->Args({8, 0, 0})
    ->Args({100, 0, 0})
    ->Args({1000, 0, 0})
    ->Args({1000, 1, 0})
    ->Args({1000, 0, 1})
    ->Args({8, 1, 0})
    ->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace localizer::engine::tws

BENCHMARK_MAIN();
