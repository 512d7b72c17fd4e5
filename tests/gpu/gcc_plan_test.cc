// GccPlan (gpu/tdoa/gcc_plan.h): the host-side half of the GPU GCC stage, which needs no
// device: it must validate like the CPU estimator, lay out the transforms like it, and key
// sessions that can share a batched cuFFT. Also: a GccBatch asked for where no device can be
// used fails with a Status, never a crash.
#include "gpu/tdoa/gcc_plan.h"

#include <gtest/gtest.h>

#include <string>
#include <unordered_set>
#include <vector>

#include "engine/sim/simulator.h"
#include "gpu/core/device.h"
#include "gpu/tdoa/gcc_batch.h"

namespace localizer::gpu {
namespace {

using engine::GccOptions;

engine::ArrayGeometry ScenarioArray(const std::string& name) {
  auto scenario = engine::MakeScenario(name);
  EXPECT_TRUE(scenario.ok());
  return *engine::ArrayGeometry::Create(scenario->sensors_m, scenario->sound_speed_mps);
}

GccOptions Options(double sample_rate_hz) {
  GccOptions o;
  o.sample_rate_hz = sample_rate_hz;
  o.band_low_hz = 300.0;
  o.band_high_hz = 3000.0;
  return o;
}

TEST(GccPlan, RejectsWhatTheCpuEstimatorRejectsWithTheSameStatus) {
  const engine::ArrayGeometry array = ScenarioArray("tetra-water");
  std::vector<GccOptions> bad;
  for (int i = 0; i < 7; ++i) bad.push_back(Options(11025.0));
  bad[0].frame_samples = 10;
  bad[1].sample_rate_hz = -1.0;
  bad[2].band_low_hz = 6000.0;
  bad[3].band_high_hz = 200.0;
  bad[4].phat_beta = 1.5;
  bad[5].lag_margin_samples = -1;
  bad[6].band_low_hz = 1000.0;  // a band narrower than one bin
  bad[6].band_high_hz = 1000.5;
  for (const GccOptions& options : bad) {
    auto cpu = engine::GccPhatEstimator::Create(array, options);
    auto plan = GccPlan::Create(array, options);
    ASSERT_FALSE(cpu.ok());
    ASSERT_FALSE(plan.ok());
    EXPECT_EQ(plan.status().code(), StatusCode::kInvalidArgument);
    EXPECT_EQ(plan.status().ToString(), cpu.status().ToString());
  }
}

// PHAT-coherence learns its weights from frame to frame; the batch keeps no such state, so a
// plan for it is refused rather than weighed some other way.
TEST(GccPlan, RefusesTheLearntCoherenceWeighting) {
  GccOptions options = Options(11025.0);
  options.weighting = engine::Weighting::kPhatCoherence;
  const auto plan = GccPlan::Create(ScenarioArray("tetra-water"), options);
  ASSERT_FALSE(plan.ok());
  EXPECT_EQ(plan.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(plan.status().message().find("phat-coherence"), std::string::npos) << plan.status().message();
}

// PHAT-share reads every channel's spectrum before it weighs a pair, which the batch does not.
TEST(GccPlan, RefusesTheShareWeighting) {
  GccOptions options = Options(11025.0);
  options.weighting = engine::Weighting::kPhatShare;
  const auto plan = GccPlan::Create(ScenarioArray("tetra-water"), options);
  ASSERT_FALSE(plan.ok());
  EXPECT_EQ(plan.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(plan.status().message().find("phat-share"), std::string::npos) << plan.status().message();
}

TEST(GccPlan, LayoutEqualsTheCpuEstimators) {
  for (const std::string& name : engine::ScenarioNames()) {
    auto scenario = engine::MakeScenario(name);
    ASSERT_TRUE(scenario.ok());
    const engine::ArrayGeometry array = ScenarioArray(name);
    for (int frame_samples : {256, 1000, 4096}) {
      GccOptions options = Options(scenario->sim.sample_rate_hz);
      options.frame_samples = frame_samples;
      options.keep_gcc = frame_samples != 1000;
      auto cpu = engine::GccPhatEstimator::Create(array, options);
      auto plan = GccPlan::Create(array, options);
      ASSERT_TRUE(cpu.ok());
      ASSERT_TRUE(plan.ok());
      EXPECT_EQ(plan->layout().fft_size, (*cpu)->fft_size());
      EXPECT_EQ(plan->layout().bin_count, (*cpu)->fft_size() / 2 + 1);
      EXPECT_EQ(plan->key().fft_size, (*cpu)->fft_size());
      EXPECT_EQ(plan->key().frame_samples, frame_samples);
      EXPECT_EQ(plan->channels(), array.sensor_count());
      ASSERT_EQ(plan->pair_count(), array.pair_count());
      std::size_t gcc_floats = 0;
      for (int p = 0; p < array.pair_count(); ++p) {
        EXPECT_EQ(plan->layout().max_lag_samples[p], (*cpu)->max_lag_samples(p));
        EXPECT_EQ(plan->sensor_of_pair(p), array.sensor_of_pair(p));
        // The window kept for each pair reaches kPeakHalfWidth lags past the searched ones.
        gcc_floats += 2 * static_cast<std::size_t>((*cpu)->max_lag_samples(p) + engine::kPeakHalfWidth) + 1;
      }
      EXPECT_EQ(plan->gcc_floats(), options.keep_gcc ? gcc_floats : 0u);
      EXPECT_EQ(plan->reference_sensor(), array.reference_sensor());
    }
  }
}

TEST(GccPlan, DifferentSessionsOfOneShapeShareAKey) {
  // tetra-water (11025 Hz, 2 m) and tetra-air (48 kHz, 0.5 m) both pad 4096 to 5120.
  GccOptions water = Options(11025.0);
  GccOptions air = Options(48000.0);
  air.weighting = engine::Weighting::kScot;
  air.band_high_hz = 8000.0;
  auto a = GccPlan::Create(ScenarioArray("tetra-water"), water);
  auto b = GccPlan::Create(ScenarioArray("tetra-air"), air);
  auto c = GccPlan::Create(ScenarioArray("turn-multipath"), water);
  ASSERT_TRUE(a.ok() && b.ok() && c.ok());
  EXPECT_EQ(a->key(), b->key());
  EXPECT_EQ(a->key().ToString(), "frame_samples=4096 fft_size=5120 channels=4");
  EXPECT_FALSE(a->key() == c->key());  // 8 channels
  std::unordered_set<GccBatchKey, GccBatchKeyHash> keys{a->key(), b->key(), c->key()};
  EXPECT_EQ(keys.size(), 2u);
}

TEST(GccBatch, CreateWithoutAUsableDeviceIsAStatus) {
  if (DeviceUnavailableReason().empty()) GTEST_SKIP() << "a device is present";
  auto plan = GccPlan::Create(ScenarioArray("tetra-water"), Options(11025.0));
  ASSERT_TRUE(plan.ok());
  auto batch = GccBatch::Create(plan->key(), 4);
  ASSERT_FALSE(batch.ok());
  EXPECT_EQ(batch.status().code(), StatusCode::kFailedPrecondition) << batch.status().ToString();
}

TEST(GccBatch, CreateRejectsBadArgumentsWithoutTouchingTheDevice) {
  EXPECT_EQ(GccBatch::Create({4096, 5120, 4}, 0).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(GccBatch::Create({4096, 5120, 4}, (1 << 16) + 1).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(GccBatch::Create({4096, 5120, 1}, 4).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(GccBatch::Create({4096, 2048, 4}, 4).status().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace localizer::gpu
