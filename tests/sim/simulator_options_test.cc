// The simulator's contract: seeds, output shape, options refused with the field named.
#include "engine/sim/simulator.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "engine/sim/propagation.h"
#include "engine/sim/source_signal.h"
#include "tests/sim/simulator_fixture.h"

namespace localizer::engine {
namespace {

using testing::kFs;
using testing::MustSimulate;
using testing::Stationary;
using testing::Tetrahedron;

TEST(Simulator, SameSeedSameSamplesOtherSeedOtherSamples) {
  const ArrayGeometry array = Tetrahedron();
  SimOptions o = Stationary(Vec3(6.0, 3.0, -7.0));
  o.snr_db = 10.0;
  o.trajectory.velocity_mps = Vec3(1.0, 0.0, 0.0);
  const SimResult a = MustSimulate(array, o);
  EXPECT_EQ(a.samples, MustSimulate(array, o).samples);
  o.seed += 1;
  const SimResult b = MustSimulate(array, o);
  ASSERT_EQ(a.samples.size(), b.samples.size());
  size_t equal = 0;
  for (size_t n = 0; n < a.samples.size(); ++n) equal += a.samples[n] == b.samples[n];
  EXPECT_LT(equal, a.samples.size() / 1000);
}

TEST(Simulator, OutputShapeAndDefaultsAreValid) {
  EXPECT_TRUE(SimOptions().Validate().ok());
  const ArrayGeometry array = Tetrahedron();
  SimOptions o = Stationary(Vec3(6.0, 3.0, -7.0));
  o.duration_s = 0.5;
  const SimResult r = MustSimulate(array, o);
  EXPECT_EQ(r.channel_count, 4);
  EXPECT_EQ(r.samples_per_channel, 5513);  // round(0.5 * 11025)
  EXPECT_EQ(r.samples.size(), 4u * 5513u);
  EXPECT_EQ(r.sample_rate_hz, kFs);
}

struct BadOption {
  const char* field;
  void (*spoil)(SimOptions&);
};

TEST(Simulator, BadOptionsAreInvalidArgumentsNamingTheField) {
  constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const BadOption cases[] = {
      {"sample_rate_hz", [](SimOptions& o) { o.sample_rate_hz = 0.0; }},
      {"sample_rate_hz", [](SimOptions& o) { o.sample_rate_hz = kNan; }},
      {"duration_s", [](SimOptions& o) { o.duration_s = -1.0; }},
      {"duration_s", [](SimOptions& o) { o.duration_s = kInf; }},
      {"duration_s", [](SimOptions& o) { o.duration_s = 1e6; }},   // 1.1e10 samples
      {"duration_s", [](SimOptions& o) { o.duration_s = 1e-6; }},  // no sample
      {"band_low_hz", [](SimOptions& o) { o.band_low_hz = -5.0; }},
      {"band_high_hz", [](SimOptions& o) { o.band_high_hz = 6000.0; }},
      {"band_low_hz", [](SimOptions& o) { o.band_low_hz = 3000.0; }},
      {"click_rate_hz",
       [](SimOptions& o) {
         o.signal = SourceSignal::kClicks;
         o.click_rate_hz = 0.0;
       }},
      {"snr_db", [](SimOptions& o) { o.snr_db = kNan; }},
      {"surface_reflection", [](SimOptions& o) { o.surface_reflection = -1.5; }},
      {"surface_z_m", [](SimOptions& o) { o.surface_z_m = kInf; }},
      {"bottom_reflection", [](SimOptions& o) { o.bottom_reflection = 1.5; }},
      {"bottom_z_m", [](SimOptions& o) { o.bottom_z_m = kNan; }},
      {"impulse_probability", [](SimOptions& o) { o.impulse_probability = 1.5; }},
      {"impulse_scale_over_noise_std", [](SimOptions& o) { o.impulse_scale_over_noise_std = 0.0; }},
      {"impulse_alpha", [](SimOptions& o) { o.impulse_alpha = 2.5; }},
      {"tone_count",
       [](SimOptions& o) {
         o.signal = SourceSignal::kTonalBroadband;
         o.tone_count = 0;
       }},
      {"tone_power_fraction",
       [](SimOptions& o) {
         o.signal = SourceSignal::kTonalBroadband;
         o.tone_power_fraction = -0.1;
       }},
      {"truth_step_s", [](SimOptions& o) { o.truth_step_s = 0.0; }},
      {"truth_step_s", [](SimOptions& o) { o.truth_step_s = 1e-6; }},
      {"trajectory.position_m", [](SimOptions& o) { o.trajectory.position_m.x() = kNan; }},
      {"trajectory.velocity_mps", [](SimOptions& o) { o.trajectory.velocity_mps.z() = kInf; }},
      {"trajectory.turn_rate_radps", [](SimOptions& o) { o.trajectory.turn_rate_radps = kNan; }},
  };
  const ArrayGeometry array = Tetrahedron();
  for (const BadOption& bad : cases) {
    SimOptions o = Stationary(Vec3(6.0, 3.0, -7.0));
    bad.spoil(o);
    const Status status = o.Validate();
    EXPECT_EQ(status.code(), StatusCode::kInvalidArgument) << bad.field;
    EXPECT_EQ(status.message().rfind(bad.field, 0), 0u) << status.message();
    const StatusOr<SimResult> r = Simulate(array, o);
    ASSERT_FALSE(r.ok()) << bad.field;
    EXPECT_EQ(r.status().code(), StatusCode::kInvalidArgument);
  }
  SimOptions o = Stationary(Vec3(6.0, 3.0, -7.0));
  o.sample_rate_hz = kNan;
  EXPECT_NE(o.Validate().message().find("nan"), std::string::npos) << o.Validate().message();
}

TEST(Simulator, OptionsBadForThisArrayAreInvalidArguments) {
  const ArrayGeometry array = Tetrahedron();
  SimOptions fast = Stationary(Vec3(6.0, 3.0, -7.0));
  fast.trajectory.velocity_mps = Vec3(800.0, 0.0, 0.0);  // above c / 2
  const StatusOr<SimResult> r1 = Simulate(array, fast);
  ASSERT_FALSE(r1.ok());
  EXPECT_EQ(r1.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(r1.status().message().find("trajectory.velocity_mps"), std::string::npos);

  SimOptions long_run = Stationary(Vec3(6.0, 3.0, -7.0));
  long_run.duration_s = 1.5e9 / kFs;  // 1.5e9 samples per channel, 6e9 over four
  ASSERT_TRUE(long_run.Validate().ok());
  const StatusOr<SimResult> r2 = Simulate(array, long_run);
  ASSERT_FALSE(r2.ok());
  EXPECT_NE(r2.status().message().find("duration_s"), std::string::npos);

  SimOptions far = Stationary(Vec3(1e12, 0.0, -7.0));
  const StatusOr<SimResult> r3 = Simulate(array, far);
  ASSERT_FALSE(r3.ok());
  EXPECT_NE(r3.status().message().find("trajectory.position_m"), std::string::npos);
}

}  // namespace
}  // namespace localizer::engine
