// EKF and UKF cost per predict + update: 8-sensor array (7 pairs), each motion model.
// Run: build/tests/bench/kalman_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <random>

#include "engine/filters/kalman_filter.h"

namespace localizer::engine {
namespace {

const char* kModels[] = {"cv", "ca", "ct", "singer"};

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
  state.SetLabel(std::string(state.range(0) == 0 ? "ekf " : "ukf ") + kModels[state.range(1)]);
}
BENCHMARK(BM_KalmanStep)->ArgsProduct({{0, 1}, {0, 1, 2, 3}});

}  // namespace
}  // namespace localizer::engine

BENCHMARK_MAIN();
