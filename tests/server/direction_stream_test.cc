// A direction session (a planar array: localization auto gives directions) streamed through
// the server gives the same sources, bit for bit, as the engine offline on the same audio.
// Scenes: far-field plane waves with exact delays (tests/doa/plane_wave.h), one 512-sample
// frame per hop, a talker moving in azimuth.
#include <gtest/gtest.h>

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
}

}  // namespace
}  // namespace localizer::server::testing
