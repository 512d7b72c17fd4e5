// Cost of one frame of direction finding (engine/doa, SRP-PHAT over every pair): 512-sample
// frames at 16 kHz (a hop of 256 is 62.5 frames per audio-second: ms per audio-second =
// CPU us per frame x 0.0625), band 100-7000 Hz,
// max_sources 4, on a 4-microphone square (ReSpeaker-style, +-4.05 cm), a 7-microphone
// circle (9.3 cm) and an 8-microphone line (4 cm spacing), with 0, 1 or 2 sources at
// 10 dB per bin. Run: build/tests/bench/doa_bench --benchmark_repetitions=5
//      --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>

#include "engine/doa/srp_phat.h"
#include "tests/doa/plane_wave.h"

namespace localizer::engine {
namespace {

std::vector<Vec3> Sensors(int kind) {
  std::vector<Vec3> s;
  if (kind == 0) {
    const double a = 0.0405;
    s = {Vec3(a, 0, 0), Vec3(0, a, 0), Vec3(-a, 0, 0), Vec3(0, -a, 0)};
  } else if (kind == 1) {
    s.push_back(Vec3::Zero());
    for (int k = 0; k < 6; ++k)
      s.push_back(0.0463 * Vec3(std::cos(k * std::numbers::pi / 3), std::sin(k * std::numbers::pi / 3), 0));
  } else {
    for (int k = 0; k < 8; ++k) s.push_back(Vec3(0.04 * k, 0, 0));
  }
  return s;
}

void BM_Analyse(benchmark::State& state) {
  testing::PlaneWaveScene scene;
  scene.sensors_m = Sensors(static_cast<int>(state.range(0)));
  std::vector<testing::PlaneSource> sources;
  for (int k = 0; k < state.range(1); ++k) sources.push_back({testing::FromAzimuthElevation(0.3 + 1.2 * k, 0.4), 1.0});
  SrpOptions options;
  options.band_low_hz = scene.band_low_hz;
  options.band_high_hz = scene.band_high_hz;
  if (state.range(0) != 2) options.source_side = Vec3::UnitZ();
  auto srp = *SrpPhat::Create(scene.sensors_m, options);
  std::vector<std::vector<float>> frames;
  for (int i = 0; i < 16; ++i) frames.push_back(testing::PlaneWaveFrame(scene, sources, 100 + i));
  size_t found = 0, i = 0;
  for (auto _ : state) {
    const auto peaks = srp.Analyse(frames[i++ % frames.size()].data());
    found += peaks->size();
  }
  state.counters["sources_per_frame"] = static_cast<double>(found) / static_cast<double>(state.iterations());
}
// (array: 0 square, 1 circle, 2 line; sources)
BENCHMARK(BM_Analyse)->ArgsProduct({{0, 1, 2}, {0, 1, 2}})->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace localizer::engine

BENCHMARK_MAIN();
