// A direction session (a planar array: localization auto gives directions) streamed through
// the server gives the same sources, bit for bit, as the engine offline on the same audio.
// Scenes: far-field plane waves with exact delays (tests/doa/plane_wave.h), one 512-sample
// frame per hop, a talker moving in azimuth.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "server/service/session_charge.h"
#include "tests/doa/near_field_scene.h"
#include "tests/doa/plane_wave.h"
#include "tests/server/service_fixture.h"

namespace localizer::server::testing {
namespace {

constexpr int kFrame = 512;
constexpr int kFrames = 60;

// A ReSpeaker-style square (+-4.05 cm) hearing one source that moves 0.01 rad per frame.
Scenario PlanarScenario() {
  engine::testing::PlaneWaveScene scene;
  scene.sensors_m = {{0.0405, 0, 0}, {0, 0.0405, 0}, {-0.0405, 0, 0}, {0, -0.0405, 0}};
  scene.frame_samples = kFrame;
  Scenario s;
  s.config.sensors_m = scene.sensors_m;
  s.config.sound_speed_mps = scene.sound_speed_mps;
  s.config.sample_rate_hz = scene.sample_rate_hz;
  s.config.frame_samples = kFrame;
  s.config.hop_samples = kFrame;  // frames do not overlap: each is one synthesised scene
  s.config.band_low_hz = scene.band_low_hz;
  s.config.band_high_hz = scene.band_high_hz;
  s.config.source_side = engine::Vec3::UnitZ();
  s.config.backend = engine::BackendChoice::kCpu;
  const int channels = static_cast<int>(scene.sensors_m.size());
  s.sim.channel_count = channels;
  s.sim.sample_rate_hz = scene.sample_rate_hz;
  s.sim.samples_per_channel = static_cast<int64_t>(kFrames) * kFrame;
  s.sim.samples.resize(static_cast<size_t>(channels * s.sim.samples_per_channel));
  for (int i = 0; i < kFrames; ++i) {
    const engine::testing::PlaneSource talker{engine::testing::FromAzimuthElevation(0.3 + 0.01 * i, 0.4), 1.0};
    const std::vector<float> frame = engine::testing::PlaneWaveFrame(scene, {talker}, 500 + static_cast<uint64_t>(i));
    for (int c = 0; c < channels; ++c) {
      std::copy_n(frame.begin() + c * kFrame, kFrame,
                  s.sim.samples.begin() + c * s.sim.samples_per_channel + static_cast<int64_t>(i) * kFrame);
    }
  }
  auto session = std::move(*engine::Session::Create(s.config));
  EXPECT_EQ(session->localization(), engine::Localization::kDirection);
  for (int64_t k = 1; k <= s.BlockCount(kFrame); ++k) {
    const std::vector<float> b = s.Block(k, kFrame);
    const engine::BlockView view{static_cast<uint64_t>(k), channels, kFrame, b.data()};
    EXPECT_TRUE(session->Process(view, &s.offline).ok());
  }
  return s;
}

TEST_F(ServiceTest, ADirectionSessionStreamsTheSameSourcesAsOffline) {
  const Scenario s = PlanarScenario();
  ASSERT_EQ(s.offline.size(), static_cast<size_t>(kFrames));
  size_t with_sources = 0;
  for (const engine::Estimate& e : s.offline) with_sources += !e.sources.empty();
  ASSERT_GT(with_sources, s.offline.size() / 2) << "the talker is followed offline";
  TestStream stream(stub_.get());
  ASSERT_TRUE(stream.Send(s.OpenRequest()));
  for (int64_t k = 1; k <= s.BlockCount(kFrame); ++k) ASSERT_TRUE(stream.Send(s.BlockRequest(k, kFrame)));
  ASSERT_TRUE(stream.Close().ok());
  const std::vector<v1::TrackResponse> responses = stream.responses();
  ASSERT_FALSE(responses.empty());
  ASSERT_TRUE(responses.front().has_opened());
  EXPECT_EQ(responses.front().opened().localization(), "direction");
  EXPECT_EQ(responses.front().opened().array_shape(), "planar");
  const auto estimates = stream.estimates();
  ASSERT_EQ(estimates.size(), s.offline.size());
  for (size_t i = 0; i < estimates.size(); ++i) ExpectSameEstimate(s.offline[i], estimates[i]);
  // Admission's size of this session's estimates (session_charge.h: max_sources sources with
  // positions) covers every response it sent.
  const int64_t charged = EstimateResponseBytes(s.config);
  int64_t largest = 0;
  for (const v1::TrackResponse& r : responses) {
    if (r.has_estimate()) largest = std::max(largest, static_cast<int64_t>(r.SpaceUsedLong()));
  }
  std::printf("direction estimate response: largest sent %lld B, charged %lld B\n", static_cast<long long>(largest),
              static_cast<long long>(charged));
  EXPECT_LE(largest, charged);
}

// Positions from a line in a stated plane (issue 18): the config's source_plane crosses the
// wire, and each source's position, covariance and range sd come back as offline.
TEST_F(ServiceTest, ALineWithASourcePlaneStreamsTheSamePositionsAsOffline) {
  engine::testing::NearFieldScene scene;
  for (int i = 0; i < 8; ++i) scene.sensors_m.emplace_back(2.0 + 0.1 * i, 1.0, 1.5);
  scene.sources_m = {engine::Vec3(2.8, 2.3, 1.5)};
  scene.room.rt60_s = 0.2;
  scene.seconds = 1.5;
  scene.seed = 23;
  Scenario s;
  s.config.sensors_m = scene.sensors_m;
  s.config.sound_speed_mps = 343.0;
  s.config.sample_rate_hz = scene.sample_rate_hz;
  s.config.frame_samples = 1024;
  s.config.hop_samples = 512;
  s.config.source_plane_point_m = engine::Vec3(0, 0, 1.5);
  s.config.source_plane_normal = engine::Vec3::UnitZ();
  s.config.source_side = engine::Vec3::UnitY();
  s.config.backend = engine::BackendChoice::kCpu;
  s.sim.channel_count = 8;
  s.sim.sample_rate_hz = scene.sample_rate_hz;
  s.sim.samples = engine::testing::RenderNearFieldScene(scene);
  s.sim.samples_per_channel = static_cast<int64_t>(s.sim.samples.size()) / 8;
  auto session = std::move(*engine::Session::Create(s.config));
  ASSERT_EQ(session->localization(), engine::Localization::kPosition);
  constexpr int kBlock = 2048;
  for (int64_t k = 1; k <= s.BlockCount(kBlock); ++k) {
    const std::vector<float> b = s.Block(k, kBlock);
    const engine::BlockView view{static_cast<uint64_t>(k), 8, static_cast<int>(b.size() / 8), b.data()};
    ASSERT_TRUE(session->Process(view, &s.offline).ok());
  }
  size_t positions = 0;
  for (const engine::Estimate& e : s.offline) {
    for (const engine::SourceEstimate& source : e.sources) positions += source.position_m.allFinite();
  }
  ASSERT_GT(positions, s.offline.size() / 2) << "positions offline";
  TestStream stream(stub_.get());
  ASSERT_TRUE(stream.Send(s.OpenRequest()));
  for (int64_t k = 1; k <= s.BlockCount(kBlock); ++k) ASSERT_TRUE(stream.Send(s.BlockRequest(k, kBlock)));
  ASSERT_TRUE(stream.Close().ok());
  const std::vector<v1::TrackResponse> responses = stream.responses();
  ASSERT_FALSE(responses.empty());
  ASSERT_TRUE(responses.front().has_opened());
  EXPECT_EQ(responses.front().opened().localization(), "position");
  EXPECT_EQ(responses.front().opened().array_shape(), "linear");
  EXPECT_EQ(responses.front().opened().effective_config().source_plane().normal().z(), 1.0);
  for (const v1::TrackResponse& r : responses) {
    EXPECT_FALSE(r.has_rejected()) << r.rejected().code() << ": " << r.rejected().message();
  }
  const auto estimates = stream.estimates();
  ASSERT_EQ(estimates.size(), s.offline.size());
  for (size_t i = 0; i < estimates.size(); ++i) ExpectSameEstimate(s.offline[i], estimates[i]);
}

}  // namespace
}  // namespace localizer::server::testing
