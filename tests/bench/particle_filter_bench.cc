// Particle filter cost per particle per step (predict + update + resample when due +
// mean/covariance), one thread, 4 sensors; the goal is <= 8 ns.
// Run: build/tests/bench/particle_filter_bench --benchmark_repetitions=5
//      --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <random>
#include <string>

#include "engine/filters/particle_filter.h"

namespace localizer::engine {
namespace {

ArrayGeometry Tetrahedron() {
  const double a = 2.0 / (2.0 * std::sqrt(2.0));
  return *ArrayGeometry::Create({Vec3(a, a, a), Vec3(a, -a, -a), Vec3(-a, a, -a), Vec3(-a, -a, a)}, 1500.0);
}

void BM_ParticleFilterStep(benchmark::State& state) {
  const int particles = static_cast<int>(state.range(0));
  const Likelihood likelihood = state.range(1) == 0 ? Likelihood::kPeak : Likelihood::kGcc;
  const ArrayGeometry array = Tetrahedron();
  ParticleFilterOptions options;
  options.particles = particles;
  options.tdoa_sigma_s = 10e-6;
  options.likelihood = likelihood;
  // Third argument 1: the default motion (acceleration levels, turn rates and speed changes:
  // ACCURACY.md, "Nineteenth pass"); 0: one std, the GPU filter's, with the fused prediction
  // (the default before it).
  if (state.range(2) == 0) options.SetSingleMotion();
  auto pf = std::move(*ParticleFilter::Create(array, options));
  const Vec3 source(6.0, -4.0, 1.0);
  TrackState belief;
  belief.mean.head<3>() = source;
  belief.covariance.diagonal() << 0.25, 0.25, 0.25, 1, 1, 1;
  (void)pf->Initialise(belief);
  // 64 noisy frames of a stationary source, cycled; GCC windows shaped like a PHAT peak.
  const double fs = 44100.0;
  std::mt19937_64 rng(1);
  std::normal_distribution<double> noise(0.0, 10e-6);
  std::vector<Measurement> frames(64);
  for (Measurement& m : frames) {
    m.sample_rate_hz = fs;
    const Eigen::VectorXd h = array.Tdoa(source);
    for (int p = 0; p < array.pair_count(); ++p) {
      PairMeasurement pm;
      pm.peak_snr = 40.0;
      pm.delay_s = h(p) + noise(rng);
      const int max_lag = static_cast<int>(std::ceil(array.max_delay_s(p) * fs)) + 2;
      pm.first_lag_samples = -max_lag;
      for (int lag = -max_lag; lag <= max_lag; ++lag) {
        pm.gcc.push_back(static_cast<float>(std::exp(-0.5 * std::pow(lag - pm.delay_s * fs, 2))));
      }
      m.pairs.push_back(pm);
    }
  }
  size_t i = 0;
  for (auto _ : state) {
    pf->Predict(2048.0 / fs);
    auto report = pf->Update(frames[i++ % frames.size()]);
    benchmark::DoNotOptimize(report);
    TrackState s = pf->State();
    benchmark::DoNotOptimize(s);
  }
  state.counters["ns_per_particle_step"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * particles * 1e-9,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.SetLabel(std::string(LikelihoodName(likelihood)) +
                 (options.single_motion() ? " one-std" : " levels+turns+speed"));
}
BENCHMARK(BM_ParticleFilterStep)->ArgsProduct({{1024, 4096, 16384}, {0, 1}, {0, 1}})->Unit(benchmark::kMicrosecond);

// A (re)start's second frame: a fix 0.41 m from a 0.45 m tetrahedron in air with the
// session's 2 m/s of unknown velocity, one 0.17-s hop, then the first update (Initialise,
// Predict and Update timed together). The cloud is decimetres wide against a 0.17-mm fix, so
// the update proposes half the particles around the fix (particle_set.h ProposeAroundFixes)
// and goes in whole; with tempering_ess_fraction 0 (second argument 0) it runs the 4 equal
// progressive-correction stages (and loses the fix; particle_start_test). 4 sensors, peak
// likelihood, default motion.
void BM_ParticleFilterStartFrame(benchmark::State& state) {
  const int particles = static_cast<int>(state.range(0));
  const double a = 0.45 / (2.0 * std::sqrt(2.0));
  const ArrayGeometry array =
      *ArrayGeometry::Create({Vec3(a, a, a), Vec3(a, -a, -a), Vec3(-a, a, -a), Vec3(-a, -a, a)}, 343.0);
  ParticleFilterOptions options;
  options.particles = particles;
  options.tdoa_sigma_s = 1e-7;
  options.tempering_ess_fraction = state.range(1) == 0 ? 0.0 : 0.05;
  auto pf = std::move(*ParticleFilter::Create(array, options));
  const Vec3 source(0.25, -0.2, 0.25);
  TrackState belief;
  belief.mean.head<3>() = source;
  belief.covariance.diagonal() << 1e-8, 1e-8, 1e-8, 4.0, 4.0, 4.0;
  Measurement m;
  m.sample_rate_hz = 48000.0;
  const Eigen::VectorXd h = array.Tdoa(source);
  for (int p = 0; p < array.pair_count(); ++p) {
    PairMeasurement pm;
    pm.peak_snr = 40.0;
    pm.delay_s = h(p);
    m.pairs.push_back(pm);
  }
  int stages = 0;
  for (auto _ : state) {
    (void)pf->Initialise(belief);
    pf->Predict(8192.0 / 48000.0);
    auto report = pf->Update(m);
    if (report.ok()) stages = report->likelihood_stages;
    benchmark::DoNotOptimize(report);
  }
  state.SetLabel(std::string(state.range(1) == 0 ? "4 equal stages" : "tempering on") + ", " + std::to_string(stages) +
                 " stage(s)");
}
BENCHMARK(BM_ParticleFilterStartFrame)->ArgsProduct({{4096, 16384}, {0, 1}})->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace localizer::engine

BENCHMARK_MAIN();
