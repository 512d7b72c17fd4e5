// Per-update cost of the attitude filters (goal: <= 0.3 µs per quaternion-filter update on
// one core; the seed's Euler EKF took 70 cycles at 74 MHz ~ 0.95 µs on an FPGA).
//
//   BM_AttitudeUpdate/<kind>/<mag>   AttitudeFilter::Update on a 285.7 Hz stream of
//                                    synthetic IMU samples (sinusoidal roll/pitch/yaw, BROAD-
//                                    like noise, seed 1), kind 0 quaternion, 1 euler; mag 0/1.
//   BM_AttitudeUpdateAndEstimate/... the same plus estimate() (Euler angles and their stds),
//                                    what the CLI does per sample.
//   BM_SoftIronFit                   one FitSoftIron() over 30 s of sums (the quaternion filter
//                                    solves it once a second with the magnetometer in use).
// Time per iteration = per update. Run:
//   build/tests/bench/attitude_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <memory>
#include <string>
#include <vector>

#include "engine/attitude/attitude_filter.h"
#include "engine/attitude/soft_iron_estimator.h"
#include "engine/sim/platform_motion.h"

namespace localizer::engine {
namespace {

constexpr double kRateHz = 285.714;

const std::vector<ImuSample>& Samples() {
  static const std::vector<ImuSample> samples = [] {
    AttitudeTrajectoryOptions motion;
    motion.amplitude_rad = {0.6, 0.5, 1.5};
    motion.frequency_hz = {0.13, 0.07, 0.05};
    ImuNoise noise;
    noise.gyro_noise_sd_rps = 0.005;
    noise.gyro_bias_rps = {0.003, -0.002, 0.004};
    noise.accel_noise_sd_mps2 = 0.05;
    noise.mag_noise_sd_uT = 0.5;
    return SynthesiseImu(AttitudeTrajectory(motion), kRateHz, 30.0, noise, 1);
  }();
  return samples;
}

std::unique_ptr<AttitudeFilter> MakeFilter(const benchmark::State& state) {
  AttitudeFilterOptions options;
  options.kind = state.range(0) == 0 ? AttitudeFilterKind::kQuaternion : AttitudeFilterKind::kEuler;
  options.use_mag = state.range(1) != 0;
  auto filter = CreateAttitudeFilter(options);
  return filter.ok() ? std::move(*filter) : nullptr;
}

template <bool kWithEstimate>
void RunUpdates(benchmark::State& state) {
  const std::vector<ImuSample>& samples = Samples();
  auto filter = MakeFilter(state);
  if (filter == nullptr) {
    state.SkipWithError("CreateAttitudeFilter failed");
    return;
  }
  size_t i = 0;
  double t_s = 0.0;
  for (auto _ : state) {
    ImuSample s = samples[i];
    s.t_s = t_s;  // the stream wraps around the recording; time keeps increasing
    t_s += 1.0 / kRateHz;
    if (++i == samples.size()) i = 0;
    const Status status = filter->Update(s);
    benchmark::DoNotOptimize(status.ok());
    if constexpr (kWithEstimate) {
      const AttitudeEstimate e = filter->estimate();
      benchmark::DoNotOptimize(e.sd_rad.data());
    }
  }
  state.SetItemsProcessed(state.iterations());
  state.SetLabel(AttitudeFilterKindName(filter->kind()) + std::string(state.range(1) ? "+mag" : ""));
}

void BM_AttitudeUpdate(benchmark::State& state) { RunUpdates<false>(state); }
void BM_AttitudeUpdateAndEstimate(benchmark::State& state) { RunUpdates<true>(state); }

void BM_SoftIronFit(benchmark::State& state) {
  AttitudeTrajectoryOptions motion;
  motion.amplitude_rad = {1.2, 0.9, 2.5};
  motion.frequency_hz = {0.13, 0.07, 0.05};
  const AttitudeTrajectory truth(motion);
  HardIronEstimator sums(20.0, 0.1, 0.1);
  for (int k = 0; k < 30 * 285; ++k) {
    const Eigen::Matrix3d r = truth.At(k / kRateHz).toRotationMatrix();
    sums.Add(r, 1.03 * (r.transpose() * Eigen::Vector3d(0.0, 17.0, -46.0)) + Eigen::Vector3d(30.0, -45.0, 12.0),
             1.0 / kRateHz);
  }
  for (auto _ : state) {
    const SoftIronFit fit = FitSoftIron(sums.sums(), SoftIronLimits{});
    benchmark::DoNotOptimize(fit.correction.data());
  }
}

BENCHMARK(BM_AttitudeUpdate)->ArgsProduct({{0, 1}, {0, 1}});
BENCHMARK(BM_SoftIronFit);
BENCHMARK(BM_AttitudeUpdateAndEstimate)->ArgsProduct({{0, 1}, {0, 1}});

}  // namespace
}  // namespace localizer::engine

BENCHMARK_MAIN();
