// GCC-PHAT stage against the bare FFTW work it cannot avoid, side by side.
//
//   BM_BareFftw/<fs>/<measure>      4 r2c + 3 c2r of N = 8192 (a 4-channel frame of 4096,
//                                   zero padded to 2x), with one plan per direction reused on
//                                   the estimator's buffer layout: the floor for the stage.
//   BM_GccPhatStage/<fs>/<measure>  GccPhatEstimator::Estimate on the same frame size:
//                                   tetrahedron with 2 m edges, c = 1500 m/s, PHAT, keep_gcc.
//   BM_StageOverBare/<fs>/<measure> the two alternated in each iteration; its counter
//                                   stage_over_bare is the ratio, robust to a busy machine.
//   BM_GccPhatCoherence/<fs>        Estimate with Weighting::kPhatCoherence (and no band), in
//                                   steady state: the per-bin weights and the coherence update.
//   BM_GccPhatShare/<fs>            Estimate with Weighting::kPhatShare (and no band): each
//                                   frame's shares (signal_share.h) and the per-bin weights.
//   BM_Despike/<coincidence>        Despike (despike.h) on the same 4 x 4096 frame, k = 5, with
//                                   the coincidence gate off (0) or at 20 samples.
//   BM_GccPhatDelayRates/<fs>       Estimate with a delay rate on every pair (SetDelayRates: each
//                                   pair also measured with its channel warped, delay_warp.h):
//                                   a compensated frame's cost, against BM_GccPhatStage.
// Estimate includes delay_sigma_s (one pass over the in-band bins per pair) and 4 candidates.
// <measure> 0 plans with FFTW_ESTIMATE (the default), 1 with FFTW_MEASURE. The goal is
// Estimate / bare FFTW <= 1.15. Run:
//   build-tdoa/tests/bench/gcc_bench
//       --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <chrono>
#include <cstring>
#include <memory>
#include <vector>

#include "engine/tdoa/despike.h"
#include "engine/tdoa/fftw_util.h"
#include "engine/tdoa/gcc_phat.h"
#include "tests/tdoa/tdoa_test_signals.h"

namespace localizer::engine {
namespace {

constexpr int kChannels = 4;
constexpr int kFrameSamples = 4096;

unsigned PlannerFlags(const benchmark::State& state) { return state.range(1) != 0 ? FFTW_MEASURE : FFTW_ESTIMATE; }

std::vector<float> BenchFrame(double sample_rate_hz, const ArrayGeometry& array) {
  testing::SignalSpec spec;
  spec.sample_rate_hz = sample_rate_hz;
  spec.band_low_hz = 200.0;
  spec.band_high_hz = 0.4 * sample_rate_hz;
  spec.frame_samples = kFrameSamples;
  const auto delays = testing::ChannelDelaysSamples(array, Vec3(12.0, -30.0, 4.0), sample_rate_hz);
  return testing::DelayedNoiseFrame(spec, delays, 20.0, 42);
}

ArrayGeometry BenchArray() { return *ArrayGeometry::Create(testing::TetrahedronSensors(), 1500.0); }

void SetCounters(benchmark::State& state) {
  state.SetItemsProcessed(state.iterations());  // frames
  state.SetBytesProcessed(state.iterations() * kChannels * kFrameSamples * sizeof(float));
}

// The transforms Estimate cannot avoid, on the estimator's buffer layout and plan flags.
class BareFftw {
 public:
  // n: the estimator's transform size (GccPhatEstimator::fft_size()).
  BareFftw(unsigned flags, const std::vector<float>& frame, int n)
      : n_(n),
        stride_((2 * (n_ / 2 + 1) + 15) / 16 * 16),  // as the estimator lays out its spectra
        padded_(AllocateFftwFloats(n_)),
        spectra_(AllocateFftwFloats(static_cast<std::size_t>(stride_) * kChannels)),
        cross_(AllocateFftwFloats(2 * (n_ / 2 + 1))),
        corr_(AllocateFftwFloats(n_)),
        forward_(PlanRealForward(n_, padded_.get(), spectra_.get(), flags)),
        inverse_(PlanRealInverse(n_, cross_.get(), corr_.get(), flags)) {
    std::memcpy(padded_.get(), frame.data(), sizeof(float) * kFrameSamples);
  }

  void Run() {
    for (int ch = 0; ch < kChannels; ++ch) {
      fftwf_execute_dft_r2c(forward_.get(), padded_.get(), AsComplex(Spectrum(ch)));
    }
    // c2r straight from channels 1..3's spectra: they are rewritten by the next r2c, so the
    // destroyed inputs never feed a later transform (no NaN or denormal slow paths).
    for (int ch = 1; ch < kChannels; ++ch) {
      fftwf_execute_dft_c2r(inverse_.get(), AsComplex(Spectrum(ch)), corr_.get());
    }
    benchmark::DoNotOptimize(corr_.get()[1]);
    benchmark::ClobberMemory();
  }

 private:
  float* Spectrum(int ch) { return spectra_.get() + static_cast<std::size_t>(ch) * stride_; }

  int n_;
  int stride_;
  FftwFloats padded_, spectra_, cross_, corr_;
  FftwPlan forward_, inverse_;
};

// The stage for this benchmark's arguments; on failure the benchmark is marked skipped.
std::unique_ptr<GccPhatEstimator> MakeStage(benchmark::State& state, const ArrayGeometry& array) {
  GccOptions options;
  options.frame_samples = kFrameSamples;
  options.sample_rate_hz = static_cast<double>(state.range(0));
  options.weighting = Weighting::kPhat;
  options.keep_gcc = true;
  options.measure_fft_plans = state.range(1) != 0;
  auto gcc = GccPhatEstimator::Create(array, options);
  if (gcc.ok()) return std::move(*gcc);
  state.SkipWithError(("GccPhatEstimator::Create failed: " + gcc.status().ToString()).c_str());
  return nullptr;
}

void BM_BareFftw(benchmark::State& state) {
  const ArrayGeometry array = BenchArray();
  auto gcc = MakeStage(state, array);
  if (!gcc) return;
  BareFftw bare(PlannerFlags(state), BenchFrame(static_cast<double>(state.range(0)), array), gcc->fft_size());
  for (auto _ : state) bare.Run();
  SetCounters(state);
}

void BM_GccPhatStage(benchmark::State& state) {
  const ArrayGeometry array = BenchArray();
  auto gcc = MakeStage(state, array);
  if (!gcc) return;
  const std::vector<float> frame = BenchFrame(static_cast<double>(state.range(0)), array);
  Measurement m;
  for (auto _ : state) {
    const Status status = gcc->Estimate(frame.data(), kFrameSamples, 0.0, &m);
    benchmark::DoNotOptimize(status.ok());
    benchmark::DoNotOptimize(m.pairs.data());
  }
  state.counters["lag_window"] = static_cast<double>(2 * gcc->max_lag_samples(0) + 1);
  SetCounters(state);
}

// Both, back to back in every iteration, so that a busy machine slows them alike: the
// counters give each one's mean time and stage_over_bare, the ratio the goal is set on.
void BM_StageOverBare(benchmark::State& state) {
  const ArrayGeometry array = BenchArray();
  auto gcc = MakeStage(state, array);
  if (!gcc) return;
  const std::vector<float> frame = BenchFrame(static_cast<double>(state.range(0)), array);
  BareFftw bare(PlannerFlags(state), frame, gcc->fft_size());
  Measurement m;
  double bare_s = 0.0;
  double stage_s = 0.0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    bare.Run();
    const auto t1 = std::chrono::steady_clock::now();
    const Status status = gcc->Estimate(frame.data(), kFrameSamples, 0.0, &m);
    const auto t2 = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(status.ok());
    bare_s += std::chrono::duration<double>(t1 - t0).count();
    stage_s += std::chrono::duration<double>(t2 - t1).count();
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["bare_us"] = 1e6 * bare_s / n;
  state.counters["stage_us"] = 1e6 * stage_s / n;
  state.counters["stage_over_bare"] = stage_s / bare_s;
}

// Estimate with `weighting` (and no band) in steady state, after 8 frames.
void WeighedSteadyState(benchmark::State& state, Weighting weighting) {
  const ArrayGeometry array = BenchArray();
  GccOptions options;
  options.frame_samples = kFrameSamples;
  options.sample_rate_hz = static_cast<double>(state.range(0));
  options.weighting = weighting;
  auto gcc = GccPhatEstimator::Create(array, options);
  if (!gcc.ok()) {
    state.SkipWithError(gcc.status().ToString().c_str());
    return;
  }
  const std::vector<float> frame = BenchFrame(options.sample_rate_hz, array);
  Measurement m;
  for (int i = 0; i < 8; ++i) (void)(*gcc)->Estimate(frame.data(), kFrameSamples, 0.0, &m);
  for (auto _ : state) {
    const Status status = (*gcc)->Estimate(frame.data(), kFrameSamples, 0.0, &m);
    benchmark::DoNotOptimize(status.ok());
  }
  SetCounters(state);
}

void BM_GccPhatCoherence(benchmark::State& state) { WeighedSteadyState(state, Weighting::kPhatCoherence); }
void BM_GccPhatShare(benchmark::State& state) { WeighedSteadyState(state, Weighting::kPhatShare); }

void BM_GccPhatDelayRates(benchmark::State& state) {
  const ArrayGeometry array = BenchArray();
  auto gcc = MakeStage(state, array);
  if (!gcc) return;
  const std::vector<float> frame = BenchFrame(static_cast<double>(state.range(0)), array);
  const std::vector<double> rates(array.pair_count(), 2e-3);  // 8 samples over the frame
  if (!gcc->SetDelayRates(rates).ok()) return state.SkipWithError("SetDelayRates failed");
  Measurement m;
  for (auto _ : state) {
    const Status status = gcc->Estimate(frame.data(), kFrameSamples, 0.0, &m);
    benchmark::DoNotOptimize(status.ok());
    benchmark::DoNotOptimize(m.pairs.data());
  }
  SetCounters(state);
}

void BM_Despike(benchmark::State& state) {
  const ArrayGeometry array = BenchArray();
  const std::vector<float> source = BenchFrame(11025.0, array);
  std::vector<float> frame = source;
  DespikeOptions options;
  options.coincidence_samples = static_cast<int>(state.range(0));
  DespikeScratch scratch;
  for (auto _ : state) {
    state.PauseTiming();
    frame = source;
    state.ResumeTiming();
    const Status status = Despike(options, frame.data(), kChannels, kFrameSamples, &scratch);
    benchmark::DoNotOptimize(status.ok());
  }
  SetCounters(state);
}

// An FFTW_ESTIMATE plan reuses FFTW_MEASURE wisdom made earlier in the process, so every
// measure=0 benchmark is registered (and runs) before any measure=1 one. For the same reason
// do not combine measure=1 with --benchmark_enable_random_interleaving.
void EstimatePlans(benchmark::internal::Benchmark* b) {
  b->ArgNames({"fs", "measure"})->Args({44100, 0})->Args({11025, 0})->Unit(benchmark::kMicrosecond);
}
void MeasuredPlans(benchmark::internal::Benchmark* b) {
  b->ArgNames({"fs", "measure"})->Args({44100, 1})->Args({11025, 1})->Unit(benchmark::kMicrosecond);
}

BENCHMARK(BM_BareFftw)->Apply(EstimatePlans);
BENCHMARK(BM_GccPhatStage)->Apply(EstimatePlans);
BENCHMARK(BM_StageOverBare)->Apply(EstimatePlans);
BENCHMARK(BM_GccPhatCoherence)->Arg(11025)->Arg(44100)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_GccPhatShare)->Arg(11025)->Arg(44100)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Despike)->Arg(0)->Arg(20)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_GccPhatDelayRates)->Apply(EstimatePlans);
BENCHMARK(BM_BareFftw)->Apply(MeasuredPlans);
BENCHMARK(BM_GccPhatStage)->Apply(MeasuredPlans);
BENCHMARK(BM_StageOverBare)->Apply(MeasuredPlans);

}  // namespace
}  // namespace localizer::engine

BENCHMARK_MAIN();
