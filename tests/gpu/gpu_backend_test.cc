// The GPU backend behind engine::Session: selection and its errors (run everywhere), and
// with a device, accuracy against the CPU, replay, batching invariance and a full bank.
#include "gpu/backend/gpu_backend.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <thread>
#include <vector>

#include "engine/models/constant_velocity.h"
#include "engine/pipeline/backend.h"
#include "engine/pipeline/session.h"
#include "engine/sim/evaluation.h"
#include "engine/sim/platform_motion.h"
#include "engine/sim/simulator.h"
#include "gpu/backend/gpu_particle_filter.h"
#include "gpu/backend/gpu_runtime.h"
#include "tests/gpu/gpu_test_util.h"
#include "tests/pipeline/scenario_run.h"

namespace localizer::gpu {
namespace {

using engine::AudioSessionConfig;
using engine::Estimate;
using engine::Session;

// The device particle filter has one acceleration std: sessions that must run it there say
// so, whatever the default (a session with acceleration levels runs its filter on the CPU).
AudioSessionConfig DeviceFilter(AudioSessionConfig config) {
  config.tracker.particle.SetSingleMotion();
  return config;
}
void DeviceFilterInPlace(AudioSessionConfig* config) { *config = DeviceFilter(*config); }

AudioSessionConfig TetraWaterConfig() {
  const engine::Scenario scenario = *engine::MakeScenario("tetra-water", 1);
  return DeviceFilter(engine::SessionConfigFor(scenario));
}

TEST(GpuBackend, GpuWithoutADeviceIsFailedPreconditionNamingTheReason) {
  ASSERT_TRUE(RegisterGpuBackend().ok());
  const std::string reason = engine::GpuUnavailableReason();
  if (reason.empty()) GTEST_SKIP() << "this machine has a usable GPU";
  AudioSessionConfig config = TetraWaterConfig();
  config.backend = engine::BackendChoice::kGpu;
  auto session = Session::Create(config);
  ASSERT_FALSE(session.ok());
  EXPECT_EQ(session.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(session.status().message().find(reason), std::string::npos) << session.status().message();
}

TEST(GpuBackend, AutoUsesTheGpuExactlyWhenOneIsUsable) {
  ASSERT_TRUE(RegisterGpuBackend().ok());
  AudioSessionConfig config = TetraWaterConfig();
  config.backend = engine::BackendChoice::kAuto;
  auto session = Session::Create(config);
  ASSERT_TRUE(session.ok()) << session.status().ToString();
  EXPECT_EQ((*session)->backend(), engine::GpuUnavailableReason().empty() ? "gpu" : "cpu");
}

TEST(GpuBackend, WithoutAProviderTheReasonSaysSo) {
  auto previous = engine::SetGpuProvider(nullptr);
  EXPECT_NE(engine::GpuUnavailableReason().find("no GPU backend"), std::string::npos);
  AudioSessionConfig config = TetraWaterConfig();
  config.backend = engine::BackendChoice::kGpu;
  EXPECT_EQ(Session::Create(config).status().code(), StatusCode::kFailedPrecondition);
  engine::SetGpuProvider(previous);
}

TEST(GpuBackend, OptionsAreValidated) {
  GpuBackendOptions bad;
  bad.batch_window_s = -1.0;
  EXPECT_EQ(RegisterGpuBackend(bad).code(), StatusCode::kInvalidArgument);
  bad = {};
  bad.max_batch_frames = 0;
  EXPECT_EQ(RegisterGpuBackend(bad).code(), StatusCode::kInvalidArgument);
  EXPECT_TRUE(RegisterGpuBackend().ok());
}

// ---- With a device --------------------------------------------------------------------

// Pooled over seeds: on the same data two CPU filters that differ only in their seed differ
// by up to 60 % in one run's RMSE and by up to 9 % pooled over 5 runs (measured on
// tetra-water/tetra-air, both likelihoods), so one run cannot resolve 10 %. The device filter
// also takes the track over from the CPU filter that acquired it (engine/filters/
// handoff_tracker.h) from a Gaussian of its state: with a CPU filter in the device's place
// that alone moves these pooled RMSEs by 0.99-1.18x for the same 10 seeds (hand-offs after 3,
// 10 or 30 steady updates: 0.99-1.47x), so the bound is 25 %. Measured on an H200
// (2026-12-04): 1.07, 1.14, 1.10, 1.10; before the hand-off and the device's delay_sigma,
// tetra-air peak was 15.9x.
TEST(GpuBackend, ScenarioRmseWithinAQuarterOfTheCpu) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  constexpr int kSeeds = 10;
  for (const char* name : {"tetra-water", "tetra-air"}) {
    for (auto likelihood : {engine::Likelihood::kPeak, engine::Likelihood::kGcc}) {
      double cpu_sq = 0.0, gpu_sq = 0.0;
      for (int seed = 1; seed <= kSeeds; ++seed) {
        const auto cpu =
            engine::TrackScenario(name, seed, likelihood, engine::BackendChoice::kCpu, engine::FilterKind::kPf,
                                  engine::MotionModelKind::kCv, DeviceFilterInPlace);
        const auto gpu =
            engine::TrackScenario(name, seed, likelihood, engine::BackendChoice::kGpu, engine::FilterKind::kPf,
                                  engine::MotionModelKind::kCv, DeviceFilterInPlace);
        ASSERT_EQ(gpu.estimates.size(), cpu.estimates.size());
        EXPECT_GE(gpu.score.scored, cpu.score.scored - 2) << name << " seed " << seed;
        cpu_sq += cpu.score.rmse_m * cpu.score.rmse_m;
        gpu_sq += gpu.score.rmse_m * gpu.score.rmse_m;
      }
      const double cpu_rmse = std::sqrt(cpu_sq / kSeeds), gpu_rmse = std::sqrt(gpu_sq / kSeeds);
      std::printf("%s %s: pooled rmse over %d seeds: cpu %.4f m, gpu %.4f m (ratio %.3f)\n", name,
                  engine::LikelihoodName(likelihood), kSeeds, cpu_rmse, gpu_rmse, gpu_rmse / cpu_rmse);
      EXPECT_LE(gpu_rmse, 1.25 * cpu_rmse) << name << " " << engine::LikelihoodName(likelihood);
    }
  }
}

// A moving array on backend gpu: the GCC runs on the device, the particle filter (which
// must follow the array every frame) on the CPU; the track matches the cpu backend's.
TEST(GpuBackend, MovingArrayKeepsTheFilterOnTheCpuAndMatchesTheCpuBackend) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  engine::Scenario scenario = *engine::MakeScenario("tetra-water", 2);
  scenario.sim.duration_s = 8.0;
  engine::AttitudeTrajectoryOptions motion;
  motion.euler_rate_rps = engine::Vec3(0.0, 0.0, 0.25);
  scenario.sim.platform_attitude = motion;
  const auto body = *engine::ArrayGeometry::Create(scenario.sensors_m, scenario.sound_speed_mps);
  const engine::SimResult sim = *engine::Simulate(body, scenario.sim);
  engine::ImuNoise noise;
  noise.with_mag = false;
  const auto imu = engine::SynthesiseImu(engine::AttitudeTrajectory(motion), 200.0, 8.0, noise, 5);
  double rmse[2] = {0.0, 0.0};
  int backend_index = 0;
  for (const engine::BackendChoice choice : {engine::BackendChoice::kCpu, engine::BackendChoice::kGpu}) {
    const std::string backend = engine::BackendChoiceName(choice);
    AudioSessionConfig config = engine::SessionConfigFor(scenario);
    config.array_in_body_frame = true;
    config.backend = choice;
    auto session = Session::Create(config);
    ASSERT_TRUE(session.ok()) << session.status().ToString();
    EXPECT_EQ((*session)->backend(), backend);
    ASSERT_TRUE((*session)->AddImu(imu).ok());
    std::vector<Estimate> estimates;
    ASSERT_TRUE(
        (*session)->Process({1, sim.channel_count, sim.samples_per_channel, sim.samples.data()}, &estimates).ok());
    const auto array_at = [&](double t_s) {
      return body.Moved(engine::AttitudeTrajectory(motion).At(t_s).toRotationMatrix(), engine::Vec3::Zero());
    };
    rmse[backend_index++] = engine::ScoreTrack(array_at, sim, estimates, 2.0).rmse_m;
  }
  std::printf("moving array: cpu %.3f m, gpu (GCC on the device) %.3f m\n", rmse[0], rmse[1]);
  EXPECT_LT(rmse[1], 1.5);
  EXPECT_LE(rmse[1], 1.25 * rmse[0] + 0.05);
}

TEST(GpuBackend, SameSeedSameEstimatesTwice) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  const auto first = engine::TrackScenario("tetra-water", 3, engine::Likelihood::kPeak, engine::BackendChoice::kGpu,
                                           engine::FilterKind::kPf, engine::MotionModelKind::kCv, DeviceFilterInPlace);
  const auto second = engine::TrackScenario("tetra-water", 3, engine::Likelihood::kPeak, engine::BackendChoice::kGpu,
                                            engine::FilterKind::kPf, engine::MotionModelKind::kCv, DeviceFilterInPlace);
  ASSERT_EQ(first.estimates.size(), second.estimates.size());
  for (size_t i = 0; i < first.estimates.size(); ++i) {
    EXPECT_EQ(first.estimates[i].state, second.estimates[i].state) << "frame " << i;
    EXPECT_EQ(first.estimates[i].delay_s, second.estimates[i].delay_s) << "frame " << i;
  }
}

// Each session of many running at once gets bit for bit what it gets alone: batches mix
// sessions, but every reduction is per session and the random numbers are keyed by seed.
TEST(GpuBackend, ThousandConcurrentSessionsGetWhatEachGetsAlone) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  const engine::Scenario scenario = *engine::MakeScenario("tetra-water", 1);
  engine::Scenario short_run = scenario;
  short_run.sim.duration_s = 1.0;
  const auto array = *engine::ArrayGeometry::Create(short_run.sensors_m, short_run.sound_speed_mps);
  const engine::SimResult sim = *engine::Simulate(array, short_run.sim);
  const engine::BlockView block{1, sim.channel_count, sim.samples_per_channel, sim.samples.data()};
  auto run = [&](uint64_t seed, std::vector<Estimate>* out) {
    AudioSessionConfig config = DeviceFilter(engine::SessionConfigFor(short_run));
    config.backend = engine::BackendChoice::kGpu;
    config.seed = seed;
    auto session = Session::Create(config);
    ASSERT_TRUE(session.ok()) << session.status().ToString();
    ASSERT_TRUE((*session)->Process(block, out).ok());
  };
  constexpr int kSessions = 1000;
  std::vector<std::vector<Estimate>> together(kSessions);
  {
    std::vector<std::thread> threads;
    for (int i = 0; i < kSessions; ++i) threads.emplace_back([&, i] { run(100 + i, &together[i]); });
    for (auto& thread : threads) thread.join();
  }
  EXPECT_GT(BatchCounts().filter_steps, BatchCounts().filter_batches) << "no batch held two sessions";
  for (int i : {0, 1, 499, 998, 999}) {
    std::vector<Estimate> alone;
    run(100 + i, &alone);
    ASSERT_EQ(alone.size(), together[i].size());
    for (size_t f = 0; f < alone.size(); ++f) {
      EXPECT_EQ(alone[f].state, together[i][f].state) << "session " << i << " frame " << f;
      EXPECT_EQ(alone[f].delay_s, together[i][f].delay_s) << "session " << i << " frame " << f;
    }
  }
}

TEST(GpuBackend, AFullBankRefusesNewSessionsAndTheOthersContinue) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  GpuBackendOptions small;
  small.bank_limit_bytes = 4 << 20;  // a few 4096-particle sessions
  ASSERT_TRUE(RegisterGpuBackend(small).ok());
  AudioSessionConfig config = TetraWaterConfig();
  config.backend = engine::BackendChoice::kGpu;
  std::vector<std::unique_ptr<Session>> open;
  Status refused = Status::Ok();
  for (int i = 0; i < 1000 && refused.ok(); ++i) {
    auto session = Session::Create(config);
    if (session.ok())
      open.push_back(std::move(session).value());
    else
      refused = session.status();
  }
  EXPECT_EQ(refused.code(), StatusCode::kResourceExhausted) << refused.ToString();
  ASSERT_FALSE(open.empty());
  const engine::Scenario scenario = *engine::MakeScenario("tetra-water", 1);
  engine::Scenario short_run = scenario;
  short_run.sim.duration_s = 0.5;
  const auto array = *engine::ArrayGeometry::Create(short_run.sensors_m, short_run.sound_speed_mps);
  const engine::SimResult sim = *engine::Simulate(array, short_run.sim);
  std::vector<Estimate> out;
  EXPECT_TRUE(open.front()->Process({1, sim.channel_count, sim.samples_per_channel, sim.samples.data()}, &out).ok());
  EXPECT_FALSE(out.empty());
  open.clear();
  ASSERT_TRUE(RegisterGpuBackend().ok());
}

// Reading a prediction costs no trip to the device: State() after Predict is the last
// moments carried forward by the constant-velocity model (F P F^T + Q) on the host, and the
// device's own prediction of the particles (a step with no usable pair) lands on those
// moments within the sampling error of 4096 particles.
TEST(GpuBackend, APredictionIsReadOnTheHostAndIsWhatTheDevicePredicts) {
  LOCALIZER_SKIP_WITHOUT_GPU();
  const engine::Scenario scenario = *engine::MakeScenario("tetra-water", 1);
  const auto array = engine::ArrayGeometry::Create(scenario.sensors_m, scenario.sound_speed_mps);
  ASSERT_TRUE(array.ok());
  auto runtime = GpuRuntime::Create(GpuBackendOptions{});
  ASSERT_TRUE(runtime.ok()) << runtime.status().ToString();
  engine::ParticleFilterOptions options;
  options.SetSingleMotion();
  options.accel_noise_mps2 = 2.0;
  auto filter = GpuParticleFilter::Create(*runtime, *array, options);
  ASSERT_TRUE(filter.ok()) << filter.status().ToString();
  engine::TrackState belief;
  belief.mean << 3.0, -2.0, 1.0, 1.5, 0.5, -0.2;
  belief.covariance = engine::Mat6::Identity();
  belief.covariance.topLeftCorner<3, 3>() *= 0.04;
  belief.covariance.bottomRightCorner<3, 3>() *= 0.25;
  ASSERT_TRUE((*filter)->Initialise(belief).ok());
  const engine::TrackState start = (*filter)->State();  // the device's moments of the drawn cloud
  const double dt_s = 0.5;
  (*filter)->Predict(dt_s);
  const uint64_t steps_before = (*runtime)->filter_stats().jobs;
  const engine::TrackState host = (*filter)->State();
  EXPECT_EQ((*runtime)->filter_stats().jobs, steps_before) << "State() went to the device";
  const engine::ConstantVelocity model{options.accel_noise_mps2};
  const engine::Mat6 f = model.Transition(dt_s);
  EXPECT_LT((host.mean - f * start.mean).norm(), 1e-9);
  EXPECT_LT((host.covariance - (f * start.covariance * f.transpose() + model.ProcessNoise(dt_s))).norm(), 1e-9);

  engine::Measurement nothing;  // every pair below any SNR: the step only predicts
  nothing.t_s = 1.0;
  nothing.sample_rate_hz = scenario.sim.sample_rate_hz;
  nothing.pairs.resize(static_cast<size_t>(array->pair_count()));
  auto report = (*filter)->Update(nothing);
  ASSERT_TRUE(report.ok()) << report.status().ToString();
  EXPECT_EQ(report->pair_count, 0);
  EXPECT_EQ((*runtime)->filter_stats().jobs, steps_before + 1);
  const engine::TrackState device = (*filter)->State();
  const double n = options.particles;
  for (int i = 0; i < 6; ++i) {
    SCOPED_TRACE("component " + std::to_string(i));
    const double var = host.covariance(i, i);
    EXPECT_NEAR(device.mean(i), host.mean(i), 5.0 * std::sqrt(var / n));
    EXPECT_NEAR(device.covariance(i, i), var, 5.0 * var * std::sqrt(2.0 / n));
  }
}

}  // namespace
}  // namespace localizer::gpu
