// GCC-PHAT stage against the bare FFTW work it cannot avoid, side by side.
//
//   BM_BareFftw/<fs>/<measure>      4 r2c + 3 c2r of N = 8192 (a 4-channel frame of 4096,
//                                   zero padded to 2x), with one plan per direction reused on
//                                   the estimator's buffer layout: the floor for the stage.
//   BM_GccPhatStage/<fs>/<measure>  GccPhatEstimator::Estimate on the same frame size:
//                                   tetrahedron with 2 m edges, c = 1500 m/s, PHAT, keep_gcc.
// <measure> 0 plans with FFTW_ESTIMATE (the default), 1 with FFTW_MEASURE. The goal is
// Estimate / bare FFTW <= 1.15. Run:
//   build-tdoa/tests/bench/gcc_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <cstring>
#include <vector>

#include "engine/tdoa/fftw_util.h"
#include "engine/tdoa/gcc_phat.h"
#include "tests/tdoa/tdoa_test_signals.h"

namespace localizer::engine {
namespace {

constexpr int kChannels = 4;
constexpr int kFrameSamples = 4096;

unsigned PlannerFlags(const benchmark::State& state) {
  return state.range(1) != 0 ? FFTW_MEASURE : FFTW_ESTIMATE;
}

std::vector<float> BenchFrame(double sample_rate_hz, const ArrayGeometry& array) {
  testing::SignalSpec spec;
  spec.sample_rate_hz = sample_rate_hz;
  spec.band_low_hz = 200.0;
  spec.band_high_hz = 0.4 * sample_rate_hz;
  spec.frame_samples = kFrameSamples;
  const auto delays = testing::ChannelDelaysSamples(array, Vec3(12.0, -30.0, 4.0), sample_rate_hz);
  return testing::DelayedNoiseFrame(spec, delays, 20.0, 42);
}

ArrayGeometry BenchArray() {
  return *ArrayGeometry::Create(testing::TetrahedronSensors(), 1500.0);
}

void SetCounters(benchmark::State& state) {
  state.SetItemsProcessed(state.iterations());  // frames
  state.SetBytesProcessed(state.iterations() * kChannels * kFrameSamples * sizeof(float));
}

void BM_BareFftw(benchmark::State& state) {
  const int n = NextPowerOfTwo(2 * kFrameSamples);
  const int bins = n / 2 + 1;
  const int stride = (2 * bins + 15) / 16 * 16;  // as the estimator lays out its spectra
  FftwFloats padded = AllocateFftwFloats(n);
  FftwFloats spectra = AllocateFftwFloats(static_cast<std::size_t>(stride) * kChannels);
  FftwFloats cross = AllocateFftwFloats(2 * bins);
  FftwFloats corr = AllocateFftwFloats(n);
  const FftwPlan forward = PlanRealForward(n, padded.get(), spectra.get(), PlannerFlags(state));
  const FftwPlan inverse = PlanRealInverse(n, cross.get(), corr.get(), PlannerFlags(state));
  const std::vector<float> frame = BenchFrame(static_cast<double>(state.range(0)), BenchArray());
  std::memcpy(padded.get(), frame.data(), sizeof(float) * kFrameSamples);

  for (auto _ : state) {
    for (int ch = 0; ch < kChannels; ++ch) {
      fftwf_execute_dft_r2c(forward.get(), padded.get(), AsComplex(spectra.get() + ch * stride));
    }
    // c2r straight from channels 1..3's spectra: they are rewritten by the next r2c, so the
    // destroyed inputs never feed a later transform (no NaN or denormal slow paths).
    for (int ch = 1; ch < kChannels; ++ch) {
      fftwf_execute_dft_c2r(inverse.get(), AsComplex(spectra.get() + ch * stride), corr.get());
    }
    benchmark::DoNotOptimize(corr.get()[1]);
    benchmark::ClobberMemory();
  }
  SetCounters(state);
}

void BM_GccPhatStage(benchmark::State& state) {
  const double sample_rate_hz = static_cast<double>(state.range(0));
  const ArrayGeometry array = BenchArray();
  GccOptions options;
  options.frame_samples = kFrameSamples;
  options.sample_rate_hz = sample_rate_hz;
  options.weighting = Weighting::kPhat;
  options.keep_gcc = true;
  options.measure_fft_plans = state.range(1) != 0;
  auto gcc = GccPhatEstimator::Create(array, options);
  if (!gcc.ok()) {
    state.SkipWithError(gcc.status().ToString().c_str());
    return;
  }
  const std::vector<float> frame = BenchFrame(sample_rate_hz, array);
  Measurement m;
  for (auto _ : state) {
    const Status status = (*gcc)->Estimate(frame.data(), kFrameSamples, 0.0, &m);
    benchmark::DoNotOptimize(status.ok());
    benchmark::DoNotOptimize(m.pairs.data());
  }
  state.counters["lag_window"] = static_cast<double>(2 * (*gcc)->max_lag_samples(0) + 1);
  SetCounters(state);
}

BENCHMARK(BM_BareFftw)->ArgNames({"fs", "measure"})->ArgsProduct({{44100, 11025}, {0, 1}})
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_GccPhatStage)->ArgNames({"fs", "measure"})->ArgsProduct({{44100, 11025}, {0, 1}})
    ->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace localizer::engine

BENCHMARK_MAIN();
