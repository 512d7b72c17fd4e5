// The particle bank's host side, without a device: a session's configuration, the step
// descriptors the kernels read (constants rounded as the CPU filter rounds them, GCC
// windows upsampled and weighted as it does), input validation, and the slot layout whose
// size Open charges against the memory limit.
//
// gpu/filters is compiled only in CUDA builds (gpu/CMakeLists.txt); elsewhere this test
// reports itself skipped.
#if defined(LOCALIZER_HAVE_CUDA)

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <utility>
#include <vector>

#include "engine/filters/gcc_upsampling.h"
#include "engine/filters/particle_set.h"
#include "gpu/filters/slot_layout.h"
#include "gpu/filters/step_builder.h"
#include "tests/gpu/pf_test_scenarios.h"

namespace localizer::gpu::pf {
namespace {

using testing::Tetrahedron;

engine::ParticleFilterOptions Options(engine::Likelihood likelihood = engine::Likelihood::kPeak) {
  engine::ParticleFilterOptions o;
  o.particles = 1000;
  o.accel_noise_mps2 = 0.7;
  o.peak_dof = 3.0;
  o.resample_threshold = 0.6;
  o.kernel_scale = 0.5;
  o.likelihood = likelihood;
  o.seed = 99;
  return o;
}

TEST(PfStepBuilder, ConfigHoldsTheGeometryRelativeToTheCentroid) {
  const engine::ArrayGeometry array = Tetrahedron(2.0, engine::Vec3(100.0, -50.0, -10.0), 1500.0);
  auto config = MakeSessionConfig(array, Options());
  ASSERT_TRUE(config.ok()) << config.status().ToString();
  EXPECT_EQ(config->pairs, 3);
  const engine::Vec3 origin = array.centroid_m();
  for (int a = 0; a < 3; ++a) {
    EXPECT_EQ(config->origin_m[a], origin(a));
    EXPECT_EQ(config->reference[a], static_cast<float>(array.sensor_m(array.reference_sensor())(a) - origin(a)));
    for (int p = 0; p < 3; ++p) {
      EXPECT_EQ(config->pair_sensor[p][a], static_cast<float>(array.sensor_m(array.sensor_of_pair(p))(a) - origin(a)));
    }
  }
  EXPECT_EQ(config->inv_c, static_cast<float>(1.0 / 1500.0));
  EXPECT_DOUBLE_EQ(config->kernel_h, std::min(0.95, 0.5 * std::pow(4.0 / (1000 * 8.0), 0.1)));
  EXPECT_DOUBLE_EQ(config->kernel_a, std::sqrt(1.0 - config->kernel_h * config->kernel_h));
}

TEST(PfStepBuilder, ConfigRejectsBadOptionsAndMoreThanSixteenSensors) {
  const engine::ArrayGeometry array = Tetrahedron(2.0, engine::Vec3::Zero(), 343.0);
  engine::ParticleFilterOptions bad = Options();
  bad.particles = 3;
  EXPECT_EQ(MakeSessionConfig(array, bad).status().code(), StatusCode::kInvalidArgument);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  for (int sensors : {16, 17}) {
    std::vector<engine::Vec3> positions;
    for (int k = 0; k < sensors; ++k) positions.emplace_back(u(rng), u(rng), u(rng));
    auto many = engine::ArrayGeometry::Create(positions, 343.0);
    ASSERT_TRUE(many.ok());
    const auto config = MakeSessionConfig(*many, Options());
    if (sensors == 16) {
      EXPECT_TRUE(config.ok());
    } else {
      EXPECT_EQ(config.status().code(), StatusCode::kInvalidArgument);
      EXPECT_NE(config.status().message().find("16"), std::string::npos) << config.status().message();
    }
  }
}

TEST(PfStepBuilder, PredictOnlyStepsCarryTheCpuProcessNoise) {
  const engine::ArrayGeometry array = Tetrahedron(2.0, engine::Vec3::Zero(), 343.0);
  const SessionConfig config = *MakeSessionConfig(array, Options());
  std::vector<float> gcc;
  SessionStep step{};
  ASSERT_TRUE(FillSessionStep(config, {0.125, nullptr, nullptr, nullptr}, &gcc, &step).ok());
  EXPECT_EQ(step.do_predict, 1);
  EXPECT_EQ(step.do_update, 0);
  EXPECT_EQ(step.dt, 0.125f);
  EXPECT_EQ(step.a_to_v, static_cast<float>(0.7 * 0.125));  // ParticleSet::Predict
  EXPECT_EQ(step.a_to_p, static_cast<float>(0.5 * 0.7 * 0.125 * 0.125));
  EXPECT_EQ(step.seed, 99u);
  EXPECT_EQ(step.resample_below, 0.6 * 1000);
  EXPECT_EQ(step.kernel, 1);
  EXPECT_EQ(step.inv_dof, static_cast<float>(1.0 / 3.0));
  EXPECT_EQ(step.half_dof_plus_1, 2.0f);
  EXPECT_TRUE(gcc.empty());
  ASSERT_TRUE(FillSessionStep(config, {0.0, nullptr, nullptr, nullptr}, &gcc, &step).ok());
  EXPECT_EQ(step.do_predict, 0);
  ASSERT_TRUE(FillSessionStep(config, {-1.0, nullptr, nullptr, nullptr}, &gcc, &step).ok());
  EXPECT_EQ(step.do_predict, 0);
  EXPECT_EQ(FillSessionStep(config, {NAN, nullptr, nullptr, nullptr}, &gcc, &step).code(),
            StatusCode::kInvalidArgument);
}

engine::Measurement PeakMeasurement(const engine::ArrayGeometry& array) {
  engine::Measurement m;
  m.sample_rate_hz = 48000.0;
  for (int p = 0; p < array.pair_count(); ++p) {
    engine::PairMeasurement pm;
    pm.sensor = array.sensor_of_pair(p);
    pm.delay_s = 1e-4 * (p + 1);
    pm.peak_snr = 30.0;
    m.pairs.push_back(pm);
  }
  return m;
}

TEST(PfStepBuilder, PeakPairsCarryDelayAndSigmaAndOnlyUsedPairsCount) {
  const engine::ArrayGeometry array = Tetrahedron(2.0, engine::Vec3::Zero(), 343.0);
  const SessionConfig config = *MakeSessionConfig(array, Options());
  const engine::Measurement m = PeakMeasurement(array);
  const int used[3] = {1, 0, 1};
  const double sigmas[3] = {2e-5, -1.0 /* unused: not checked */, 4e-5};
  std::vector<float> gcc;
  SessionStep step{};
  ASSERT_TRUE(FillSessionStep(config, {0.0, &m, used, sigmas}, &gcc, &step).ok());
  EXPECT_EQ(step.do_update, 1);
  EXPECT_EQ(step.pairs, 3);
  for (int p = 0; p < 3; ++p) {
    EXPECT_EQ(step.pair[p].used, used[p]);
    EXPECT_EQ(step.pair[p].gcc_offset, -1);
    for (int a = 0; a < 3; ++a) EXPECT_EQ(step.pair[p].sensor[a], config.pair_sensor[p][a]);
  }
  EXPECT_EQ(step.pair[0].delay_s, static_cast<float>(1e-4));
  EXPECT_EQ(step.pair[0].half_delay_s, 0.5f * static_cast<float>(1e-4));
  EXPECT_EQ(step.pair[2].inv_sigma, static_cast<float>(1.0 / 4e-5));
  for (int p = 3; p < kMaxPairs; ++p) EXPECT_EQ(step.pair[p].used, 0);
  const int none[3] = {0, 0, 0};
  ASSERT_TRUE(FillSessionStep(config, {0.1, &m, none, sigmas}, &gcc, &step).ok());
  EXPECT_EQ(step.do_update, 0);  // no used pair: predict only
  EXPECT_EQ(step.do_predict, 1);
}

// Motion blur (engine ParticleFilterOptions::motion_blur, off by default): a used pair carries the variance
// the engine's filter gives its peak per (s/s)^2 of delay rate, K V with K = min(1, 2 /
// peak_snr); a front end that states no window time (V = 0) leaves it off.
TEST(PfStepBuilder, UsedPairsCarryTheEnginesMotionBlur) {
  const engine::ArrayGeometry array = Tetrahedron(2.0, engine::Vec3::Zero(), 343.0);
  engine::ParticleFilterOptions blurred = Options();
  blurred.motion_blur = 1.0;  // off by default
  SessionConfig config = *MakeSessionConfig(array, blurred);
  engine::Measurement m = PeakMeasurement(array);
  m.window_time_var_s2 = 0.02 * 0.1 * 0.1;
  const int used[3] = {1, 1, 1};
  const double sigmas[3] = {2e-5, 2e-5, 2e-5};
  std::vector<float> gcc;
  SessionStep step{};
  ASSERT_TRUE(FillSessionStep(config, {0.0, &m, used, sigmas}, &gcc, &step).ok());
  for (int p = 0; p < 3; ++p) {
    EXPECT_FLOAT_EQ(step.pair[p].blur_var_s2, static_cast<float>(m.window_time_var_s2 * 2.0 / 30.0)) << p;
  }
  const engine::Measurement stated = m;
  m.window_time_var_s2 = 0.0;
  ASSERT_TRUE(FillSessionStep(config, {0.0, &m, used, sigmas}, &gcc, &step).ok());
  for (int p = 0; p < 3; ++p) EXPECT_EQ(step.pair[p].blur_var_s2, 0.0f) << p;
  // The default (off) leaves it out whatever the front end states.
  config = *MakeSessionConfig(array, Options());
  ASSERT_TRUE(FillSessionStep(config, {0.0, &stated, used, sigmas}, &gcc, &step).ok());
  for (int p = 0; p < 3; ++p) EXPECT_EQ(step.pair[p].blur_var_s2, 0.0f) << p;
}

TEST(PfStepBuilder, BadMeasurementsAreInvalidArguments) {
  const engine::ArrayGeometry array = Tetrahedron(2.0, engine::Vec3::Zero(), 343.0);
  const SessionConfig config = *MakeSessionConfig(array, Options());
  engine::Measurement m = PeakMeasurement(array);
  const int used[3] = {1, 1, 1};
  double sigmas[3] = {2e-5, 2e-5, 2e-5};
  std::vector<float> gcc;
  SessionStep step{};
  EXPECT_EQ(FillSessionStep(config, {0.0, &m, nullptr, sigmas}, &gcc, &step).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(FillSessionStep(config, {0.0, &m, used, nullptr}, &gcc, &step).code(), StatusCode::kInvalidArgument);
  sigmas[1] = 0.0;
  EXPECT_EQ(FillSessionStep(config, {0.0, &m, used, sigmas}, &gcc, &step).code(), StatusCode::kInvalidArgument);
  sigmas[1] = 2e-5;
  m.pairs[2].delay_s = NAN;
  EXPECT_EQ(FillSessionStep(config, {0.0, &m, used, sigmas}, &gcc, &step).code(), StatusCode::kInvalidArgument);
  m.pairs.pop_back();
  EXPECT_EQ(FillSessionStep(config, {0.0, &m, used, sigmas}, &gcc, &step).code(), StatusCode::kInvalidArgument);
}

TEST(PfStepBuilder, GccPairsCarryTheCpusUpsampledWindowAndGain) {
  const engine::ArrayGeometry array = Tetrahedron(2.0, engine::Vec3::Zero(), 343.0);
  const SessionConfig config = *MakeSessionConfig(array, Options(engine::Likelihood::kGcc));
  engine::Measurement m = PeakMeasurement(array);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-0.1f, 0.3f);
  const int lengths[3] = {41, 3 /* too short: peak likelihood */, 57};
  for (int p = 0; p < 3; ++p) {
    m.pairs[p].first_lag_samples = -(lengths[p] / 2);
    for (int k = 0; k < lengths[p]; ++k) m.pairs[p].gcc.push_back(u(rng));
    m.pairs[p].gcc[lengths[p] / 3] = 1.0f;
  }
  const int used[3] = {1, 1, 1};
  const double sigmas[3] = {2e-5, 3e-5, 1e-5};
  std::vector<float> gcc = {7.0f};  // windows are appended after what is there
  SessionStep step{};
  ASSERT_TRUE(FillSessionStep(config, {0.0, &m, used, sigmas}, &gcc, &step).ok());
  EXPECT_EQ(step.pair[1].gcc_offset, -1);
  size_t expected_offset = 1;
  for (int p : {0, 2}) {
    std::vector<float> fine;
    engine::UpsampleGcc(m.pairs[p].gcc, engine::kGccUpsampling, &fine);
    const PairParams& pp = step.pair[p];
    ASSERT_EQ(pp.gcc_offset, static_cast<int>(expected_offset));
    for (size_t k = 0; k < fine.size(); ++k) ASSERT_EQ(gcc[expected_offset + k], fine[k]);
    expected_offset += fine.size();
    // ParticleSet::Weigh's constants.
    EXPECT_EQ(pp.lag_scale, static_cast<float>(48000.0 * engine::kGccUpsampling));
    EXPECT_EQ(pp.lag0, static_cast<float>(m.pairs[p].first_lag_samples * engine::kGccUpsampling));
    EXPECT_EQ(pp.last_lag, static_cast<float>(fine.size() - 3) - 1e-3f);
    EXPECT_EQ(pp.gcc_gain, static_cast<float>(engine::GccGain(fine, sigmas[p] * 48000.0 * engine::kGccUpsampling,
                                                              config.options.gcc_sharpness)));
  }
  EXPECT_EQ(gcc.size(), expected_offset);
  m.sample_rate_hz = 0.0;
  EXPECT_EQ(FillSessionStep(config, {0.0, &m, used, sigmas}, &gcc, &step).code(), StatusCode::kInvalidArgument);
}

TEST(PfSlotLayout, ArraysAreAlignedDisjointAndAboutSixtyFourBytesPerParticle) {
  for (int n : {16, 255, 256, 257, 4096, 1000000}) {
    const SlotLayout l = SlotLayout::For(n);
    EXPECT_EQ(l.blocks, (n + kBlockThreads - 1) / kBlockThreads);
    std::vector<std::pair<size_t, size_t>> ranges;  // [begin, end)
    for (const auto& buffer : l.state) {
      for (size_t column : buffer) ranges.emplace_back(column, column + n * sizeof(float));
    }
    ranges.emplace_back(l.logw, l.logw + n * sizeof(float));
    ranges.emplace_back(l.w, l.w + n * sizeof(float));
    ranges.emplace_back(l.cumsum, l.cumsum + n * sizeof(double));
    ranges.emplace_back(l.partials, l.partials + l.blocks * sizeof(BlockPartial));
    std::sort(ranges.begin(), ranges.end());
    for (size_t k = 0; k < ranges.size(); ++k) {
      EXPECT_EQ(ranges[k].first % 256, 0u);
      if (k + 1 < ranges.size()) {
        EXPECT_LE(ranges[k].second, ranges[k + 1].first);
      }
    }
    EXPECT_LE(ranges.back().second, l.bytes);
    const size_t payload = 64u * n + l.blocks * sizeof(BlockPartial);
    EXPECT_GE(l.bytes, payload);
    EXPECT_LE(l.bytes, payload + 16 * 256);
    unsigned char* base = reinterpret_cast<unsigned char*>(size_t{1} << 20);
    const SlotView v0 = l.View(base, 0), v1 = l.View(base, 1);
    for (int c = 0; c < 6; ++c) {
      EXPECT_EQ(v0.state[c], v1.next[c]);
      EXPECT_EQ(v0.next[c], v1.state[c]);
      EXPECT_NE(v0.state[c], v0.next[c]);
    }
    EXPECT_EQ(v0.particles, n);
    EXPECT_EQ(v0.blocks, l.blocks);
  }
}

}  // namespace
}  // namespace localizer::gpu::pf

#else  // !LOCALIZER_HAVE_CUDA

#include <gtest/gtest.h>

TEST(PfStepBuilder, NeedsTheCudaBuild) { GTEST_SKIP() << "built without CUDA: gpu/filters is not compiled"; }

#endif  // LOCALIZER_HAVE_CUDA
