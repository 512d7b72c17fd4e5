// EKF and UKF cost per predict + update: 8-sensor array (7 pairs), each motion model; the
// IMM (cv + ct modes) and the multiple-model particle filter (4 hypotheses) against the
// particle filter, per predict + update + estimate on the straight-then-turn scene of
// tests/filters/manoeuvre_track.h.
// Run: build/tests/bench/kalman_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <random>

#include "engine/filters/imm_filter.h"
#include "engine/filters/kalman_filter.h"
#include "engine/filters/multi_model_pf.h"
#include "tests/filters/manoeuvre_track.h"

namespace localizer::engine {
namespace {

const MotionModelKind kModels[] = {MotionModelKind::kCv, MotionModelKind::kCa, MotionModelKind::kCt,
                                   MotionModelKind::kSinger};

void BM_KalmanStep(benchmark::State& state) {
  std::vector<Vec3> sensors;
  for (int i = 0; i < 8; ++i) sensors.emplace_back(i & 1 ? 1.0 : -1.0, i & 2 ? 1.0 : -1.0, i & 4 ? 0.8 : -0.8);
  const ArrayGeometry array = *ArrayGeometry::Create(sensors, 1500.0);
  KalmanOptions o;
  o.variant = state.range(0) == 0 ? KalmanVariant::kExtended : KalmanVariant::kUnscented;
  o.motion_model = kModels[state.range(1)];
  o.tdoa_sigma_s = 2e-6;
  auto filter = std::move(*KalmanFilter::Create(array, o));
  TrackState belief;
  belief.mean << 5, 5, 0, 0, 0, 0;
  belief.covariance = Mat6::Identity();
  (void)filter->Initialise(belief);
  const Vec3 p(5, 5, 0);
  const Eigen::VectorXd t = array.Tdoa(p);
  Measurement m;
  m.sample_rate_hz = 48000.0;
  std::mt19937_64 rng(1);
  std::normal_distribution<double> noise(0.0, 2e-6);
  for (int k = 0; k < array.pair_count(); ++k) {
    PairMeasurement pair;
    pair.delay_s = t(k) + noise(rng);
    pair.peak_snr = 50.0;
    m.pairs.push_back(pair);
  }
  for (auto _ : state) {
    filter->Predict(0.05);
    benchmark::DoNotOptimize(filter->Update(m));
  }
  state.SetLabel(std::string(state.range(0) == 0 ? "ekf " : "ukf ") + MotionModelKindName(kModels[state.range(1)]));
}
BENCHMARK(BM_KalmanStep)->ArgsProduct({{0, 1}, {0, 1, 2, 3}});

// One tracker over the manoeuvre scene's frames, cycled (restarted at the end).
void StepThrough(benchmark::State& state, Tracker& tracker) {
  const testing::ManoeuvreScene scene;
  const auto truth = testing::MakeManoeuvre(testing::BoxArray(), scene, 1);
  size_t i = 0;
  for (auto _ : state) {
    if (i % truth.size() == 0) (void)tracker.Initialise(testing::StartBelief());
    tracker.Predict(scene.dt_s);
    benchmark::DoNotOptimize(tracker.Update(truth[i++ % truth.size()].measurement));
    benchmark::DoNotOptimize(tracker.State());
  }
}

void BM_ImmStep(benchmark::State& state) {
  ImmOptions o;
  o.kalman.variant = state.range(0) == 0 ? KalmanVariant::kExtended : KalmanVariant::kUnscented;
  o.kalman.tdoa_sigma_s = 2e-6;
  auto imm = std::move(*ImmFilter::Create(testing::BoxArray(), o));
  StepThrough(state, *imm);
  state.SetLabel(state.range(0) == 0 ? "imm ekf cv+ct" : "imm ukf cv+ct");
}
BENCHMARK(BM_ImmStep)->Arg(0)->Arg(1);

// range(0): 0 the particle filter, 1 the multiple-model one; range(1): particles.
void BM_ParticleStep(benchmark::State& state) {
  ParticleFilterOptions o;
  o.particles = static_cast<int>(state.range(1));
  o.accel_noise_mps2 = 0.05;
  o.tdoa_sigma_s = 2e-6;
  std::unique_ptr<Tracker> tracker;
  if (state.range(0) == 0) {
    tracker = std::move(*ParticleFilter::Create(testing::BoxArray(), o));
  } else {
    MultiModelPfOptions mo;
    mo.particle = o;
    tracker = std::move(*MultiModelParticleFilter::Create(testing::BoxArray(), mo));
  }
  StepThrough(state, *tracker);
  state.SetLabel(state.range(0) == 0 ? "pf" : "mmpf (4 hypotheses)");
}
BENCHMARK(BM_ParticleStep)->ArgsProduct({{0, 1}, {2048, 16384}});

}  // namespace
}  // namespace localizer::engine

BENCHMARK_MAIN();
