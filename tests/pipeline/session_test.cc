// The session's contracts: validation that never corrupts state, framing independent of
// block sizes, replay from the seed, and clear errors for unusable configurations.
#include "engine/pipeline/session.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "engine/sim/simulator.h"
#include "engine/tdoa/gcc_math.h"

namespace localizer::engine {
namespace {

// The frames' taper follows the overlap: the widest Tukey window whose hop-shifted copies sum
// to a constant (Hann at 50 %), never narrower than GccOptions' 0.2 (a frame nothing overlaps).
TEST(SessionConfig, TheFramesTaperIsTheWidestThatTheOverlapKeepsConstant) {
  AudioSessionConfig c;
  c.frame_samples = 4096;
  for (const auto& [hop, taper] :
       {std::pair{2048, 1.0}, std::pair{1024, 1.0}, std::pair{3072, 0.5}, std::pair{4096, 0.2}, std::pair{4000, 0.2}}) {
    c.hop_samples = hop;
    EXPECT_DOUBLE_EQ(c.GccOptionsFor().taper_fraction, taper) << "hop " << hop;
  }
  // Tukey 0.5 at a 3/4-frame hop: each sample's gains over the frames holding it sum to 1.
  const int n = 4096, hop = 3072, edge = TaperEdgeSamples(n, 0.5f);
  for (int i = hop; i < n; i += 97) {
    EXPECT_NEAR(TaperGain(i, n, edge) + TaperGain(i - hop, n, edge), 1.0, 2e-3) << "sample " << i;
  }
}

struct Fixture {
  Scenario scenario;
  SimResult sim;
};

const Fixture& WaterScene() {
  static const Fixture f = [] {
    Fixture x;
    x.scenario = *MakeScenario("tetra-water", 3);
    x.scenario.sim.duration_s = 4.0;
    auto array = ArrayGeometry::Create(x.scenario.sensors_m, x.scenario.sound_speed_mps);
    x.sim = *Simulate(*array, x.scenario.sim);
    return x;
  }();
  return f;
}

AudioSessionConfig ConfigFor(const Scenario& s) {
  AudioSessionConfig c;
  c.sensors_m = s.sensors_m;
  c.sound_speed_mps = s.sound_speed_mps;
  c.sample_rate_hz = s.sim.sample_rate_hz;
  c.frame_samples = 2048;
  c.hop_samples = 1024;
  c.tracker.particle.particles = 1024;
  c.seed = 9;
  return c;
}

// Copies samples [from, from + n) of every channel into a channel-major block buffer.
std::vector<float> Slice(const SimResult& sim, int64_t from, int64_t n) {
  std::vector<float> out(static_cast<size_t>(n * sim.channel_count));
  for (int c = 0; c < sim.channel_count; ++c) {
    const float* src = sim.samples.data() + c * sim.samples_per_channel + from;
    std::copy(src, src + n, out.begin() + c * n);
  }
  return out;
}

std::vector<Estimate> RunInBlocks(const AudioSessionConfig& config, const SimResult& sim,
                                  const std::vector<int64_t>& sizes) {
  auto session = std::move(*Session::Create(config));
  std::vector<Estimate> out;
  int64_t at = 0;
  uint64_t seq = 1;
  for (size_t i = 0; at < sim.samples_per_channel; ++i) {
    const int64_t n = std::min(sizes[i % sizes.size()], sim.samples_per_channel - at);
    const std::vector<float> block = Slice(sim, at, n);
    const BlockView view{seq++, sim.channel_count, n, block.data()};
    EXPECT_TRUE(session->Process(view, &out).ok());
    at += n;
  }
  return out;
}

void ExpectSameEstimates(const std::vector<Estimate>& a, const std::vector<Estimate>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].t_s, b[i].t_s) << i;
    EXPECT_EQ(a[i].state, b[i].state) << i;
    EXPECT_EQ(a[i].delay_s, b[i].delay_s) << i;
  }
}

TEST(Session, OneEstimatePerFrameAtTheFrameCentre) {
  const Fixture& f = WaterScene();
  const AudioSessionConfig config = ConfigFor(f.scenario);
  const std::vector<Estimate> out = RunInBlocks(config, f.sim, {f.sim.samples_per_channel});
  const int64_t expected = (f.sim.samples_per_channel - config.frame_samples) / config.hop_samples + 1;
  ASSERT_EQ(static_cast<int64_t>(out.size()), expected);
  for (size_t i = 0; i < out.size(); ++i) {
    EXPECT_EQ(out[i].frame_index, i);
    EXPECT_DOUBLE_EQ(out[i].t_s, (static_cast<double>(i) * config.hop_samples + 0.5 * (config.frame_samples - 1)) /
                                     config.sample_rate_hz);
    EXPECT_EQ(out[i].delay_s.size(), 3u);
    EXPECT_GT(out[i].timings.tdoa_s, 0.0);
  }
  EXPECT_TRUE(out.back().initialised);
}

TEST(Session, BlockSizesDoNotChangeTheEstimates) {
  const Fixture& f = WaterScene();
  const AudioSessionConfig config = ConfigFor(f.scenario);
  const auto whole = RunInBlocks(config, f.sim, {f.sim.samples_per_channel});
  ExpectSameEstimates(whole, RunInBlocks(config, f.sim, {1, 777, 4096, 13, 2500}));
  ExpectSameEstimates(whole, RunInBlocks(config, f.sim, {1024}));
}

TEST(Session, SameSeedReplaysOtherSeedDiffers) {
  const Fixture& f = WaterScene();
  AudioSessionConfig config = ConfigFor(f.scenario);
  const auto a = RunInBlocks(config, f.sim, {3000});
  ExpectSameEstimates(a, RunInBlocks(config, f.sim, {3000}));
  config.seed = 10;
  const auto c = RunInBlocks(config, f.sim, {3000});
  EXPECT_NE(a.back().state, c.back().state);
}

TEST(Session, BadBlocksAreRejectedAndTheSessionSurvives) {
  const Fixture& f = WaterScene();
  const AudioSessionConfig config = ConfigFor(f.scenario);
  const int64_t n = 5000;
  const std::vector<float> first = Slice(f.sim, 0, n), second = Slice(f.sim, n, n);

  auto clean = std::move(*Session::Create(config));
  std::vector<Estimate> clean_out;
  ASSERT_TRUE(clean->Process({1, 4, n, first.data()}, &clean_out).ok());
  ASSERT_TRUE(clean->Process({2, 4, n, second.data()}, &clean_out).ok());

  auto session = std::move(*Session::Create(config));
  std::vector<Estimate> out;
  ASSERT_TRUE(session->Process({1, 4, n, first.data()}, &out).ok());
  const size_t before = out.size();

  std::vector<float> poisoned = second;
  poisoned[3 * n + 17] = std::nanf("");
  Status s = session->Process({2, 4, n, poisoned.data()}, &out);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("channel 3, sample 17"), std::string::npos) << s.message();
  poisoned[3 * n + 17] = INFINITY;
  EXPECT_EQ(session->Process({2, 4, n, poisoned.data()}, &out).code(), StatusCode::kInvalidArgument);

  s = session->Process({2, 3, n, second.data()}, &out);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("channel_count is 3"), std::string::npos) << s.message();
  s = session->Process({1, 4, n, second.data()}, &out);  // sequence not increasing
  EXPECT_NE(s.message().find("sequence 1"), std::string::npos) << s.message();
  EXPECT_EQ(session->Process({2, 4, 0, second.data()}, &out).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(session->Process({2, 4, n, nullptr}, &out).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(out.size(), before);  // nothing was emitted by the rejected blocks

  ASSERT_TRUE(session->Process({2, 4, n, second.data()}, &out).ok());
  ExpectSameEstimates(clean_out, out);  // as if the bad blocks never came
}

TEST(Session, ConfigurationErrorsNameTheField) {
  const Fixture& f = WaterScene();
  AudioSessionConfig c = ConfigFor(f.scenario);
  c.sensors_m.pop_back();
  c.localization = Localization::kPosition;  // three sensors give directions, not a position
  auto s = Session::Create(c);
  EXPECT_EQ(s.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.status().message().find("sensors_m"), std::string::npos);
  c.localization = Localization::kAuto;
  EXPECT_TRUE(Session::Create(c).ok())
      << Session::Create(c).status().ToString();  // directions (direction_session_test.cc)

  c = ConfigFor(f.scenario);
  c.hop_samples = c.frame_samples + 1;
  EXPECT_NE(Session::Create(c).status().message().find("hop_samples"), std::string::npos);
  c = ConfigFor(f.scenario);
  c.sample_rate_hz = -1;
  EXPECT_NE(Session::Create(c).status().message().find("sample_rate_hz"), std::string::npos);
  c = ConfigFor(f.scenario);
  c.cross_pairs_max_sensors = 17;  // checked with the front end's options (GccOptions::Validate)
  EXPECT_EQ(Session::Create(c).status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(Session::Create(c).status().message().find("cross_pairs_max_sensors"), std::string::npos);
  c = ConfigFor(f.scenario);
  c.sensors_m[3] = (c.sensors_m[0] + c.sensors_m[1]) / 2.0;  // three collinear, four coplanar
  c.localization = Localization::kPosition;
  EXPECT_NE(Session::Create(c).status().message().find("planar"), std::string::npos);
}

TEST(Session, GpuWithoutOneIsAClearErrorNeverAFallback) {
  const Fixture& f = WaterScene();
  AudioSessionConfig c = ConfigFor(f.scenario);
  c.backend = BackendChoice::kGpu;
  auto s = Session::Create(c);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(s.status().message().find("gpu"), std::string::npos);
  EXPECT_EQ(ParseBackendChoice("tpu", "backend").status().code(), StatusCode::kInvalidArgument);
  c.backend = BackendChoice::kAuto;
  EXPECT_TRUE(Session::Create(c).ok());
}

// The weightings the device GCC does not compute: refused on gpu (whether or not a device is
// present), run on the CPU with auto.
TEST(Session, CpuOnlyWeightingsAreRefusedOnTheGpuByName) {
  const Fixture& f = WaterScene();
  for (Weighting w : {Weighting::kPhatCoherence, Weighting::kPhatShare}) {
    AudioSessionConfig c = ConfigFor(f.scenario);
    c.weighting = w;
    c.backend = BackendChoice::kGpu;
    auto s = Session::Create(c);
    ASSERT_FALSE(s.ok());
    EXPECT_EQ(s.status().code(), StatusCode::kFailedPrecondition);
    EXPECT_NE(s.status().message().find(WeightingName(w)), std::string::npos) << s.status().message();
    c.backend = BackendChoice::kAuto;
    EXPECT_TRUE(Session::Create(c).ok()) << WeightingName(w);
  }
}

}  // namespace
}  // namespace localizer::engine

namespace localizer::engine {
namespace {

// The 8-hydrophone array of turn-multipath (no mirror ambiguity as with 4 sensors), without
// the surface echo, at 20 dB.
Scenario EightHydrophones() {
  Scenario s = *MakeScenario("turn-multipath", 1);
  s.sim.surface_reflection_enabled = false;
  s.sim.snr_db = 20.0;
  return s;
}

// A stationary broadband source at `source_m` heard by `base`'s array for `duration_s`.
SimResult StationaryScene(const Scenario& base, const Vec3& source_m, double duration_s, uint64_t seed) {
  SimOptions o = base.sim;
  o.trajectory = Trajectory{};
  o.trajectory.position_m = source_m;
  o.duration_s = duration_s;
  o.seed = seed;
  return *Simulate(*ArrayGeometry::Create(base.sensors_m, base.sound_speed_mps), o);
}

TEST(Session, StartsFromAConfiguredRegionWithoutWaitingForAFix) {
  const Scenario base = EightHydrophones();
  const Vec3 source(3.0, 2.0, -6.0);
  const SimResult sim = StationaryScene(base, source, 4.0, 5);
  AudioSessionConfig c = ConfigFor(base);
  c.band_low_hz = base.sim.band_low_hz;
  c.band_high_hz = base.sim.band_high_hz;
  c.min_pair_quality = 1e9;              // no fix is ever good enough: only the region can start it
  c.tracker.particle.particles = 16384;  // a 20 x 20 x 14 m box needs them to find a 2 cm TDOA peak
  c.init_region_min_m = Vec3(-10, -10, -15);
  c.init_region_max_m = Vec3(10, 10, -1);
  const std::vector<Estimate> out = RunInBlocks(c, sim, {4096});
  ASSERT_FALSE(out.empty());
  EXPECT_TRUE(out.front().initialised);
  EXPECT_LT((out.back().state.head<3>() - source).norm(), 0.5) << out.back().state.transpose();

  c.init_region_max_m.x() = -11;  // min > max
  EXPECT_EQ(Session::Create(c).status().code(), StatusCode::kInvalidArgument);
}

// A session on recording a then b (its source moved from first to second).
void ExpectRecoversFromAJump(const AudioSessionConfig& c, const SimResult& a, const SimResult& b, const Vec3& first,
                             const Vec3& second) {
  auto session = std::move(*Session::Create(c));
  std::vector<Estimate> out;
  const std::vector<float> pa = Slice(a, 0, a.samples_per_channel), pb = Slice(b, 0, b.samples_per_channel);
  ASSERT_TRUE(session->Process({1, 8, a.samples_per_channel, pa.data()}, &out).ok());
  ASSERT_LT((out.back().state.head<3>() - first).norm(), 0.5);
  const size_t before = out.size();
  ASSERT_TRUE(session->Process({2, 8, b.samples_per_channel, pb.data()}, &out).ok());
  int reinitialisations = 0;
  for (size_t i = before; i < out.size(); ++i) reinitialisations += out[i].reinitialised ? 1 : 0;
  EXPECT_GE(reinitialisations, 1);
  EXPECT_LT((out.back().state.head<3>() - second).norm(), 0.5);
}

// The source "jumps" (one recording cut into another): the innovations explode, the
// divergence test fires and the filter restarts from a fix near the new position. The
// recovery is the session's, so every filter type gets it.
TEST(Session, DivergenceReinitialisesFromTheCurrentFix) {
  const Scenario base = EightHydrophones();
  const Vec3 first(3.0, 2.0, -6.0), second(-3.0, -2.5, -12.0);
  const SimResult a = StationaryScene(base, first, 4.0, 6), b = StationaryScene(base, second, 4.0, 7);
  for (const FilterKind filter :
       {FilterKind::kPf, FilterKind::kEkf, FilterKind::kUkf, FilterKind::kMmpf, FilterKind::kImm}) {
    SCOPED_TRACE(FilterKindName(filter));
    AudioSessionConfig c = ConfigFor(base);
    c.band_low_hz = base.sim.band_low_hz;
    c.band_high_hz = base.sim.band_high_hz;
    c.tracker.kind = filter;
    ExpectRecoversFromAJump(c, a, b, first, second);
  }
}

}  // namespace
}  // namespace localizer::engine
