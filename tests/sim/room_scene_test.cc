// Room scenes (engine/sim/room_scene.h): what the sensors record is the room's physics (the
// direct path's delay between sensors), bursts sound only when they say, a seed replays,
// and a bad scene is refused naming the field.
#include "engine/sim/room_scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace localizer::engine {
namespace {

RoomScene OneSource(RoomSignal signal) {
  RoomScene scene;
  scene.room.size_m = Vec3(6.0, 5.0, 3.0);
  scene.room.rt60_s = 0.0;
  scene.room.sound_speed_mps = 343.0;
  scene.sample_rate_hz = 16000.0;
  scene.duration_s = 2.0;
  scene.noise_db = -40.0;
  RoomSceneSource s;
  s.position_m = Vec3(4.0, 3.0, 1.5);
  s.signal = signal;
  scene.sources = {s};
  return scene;
}

// Sensor 1 hears the source this many samples after sensor 0: the time-domain
// cross-correlation's largest lag within +-max_lag.
int MeasuredLag(const std::vector<float>& x, int64_t n, int max_lag) {
  double best = -1e300;
  int best_lag = 0;
  for (int lag = -max_lag; lag <= max_lag; ++lag) {
    double sum = 0.0;
    for (int64_t t = max_lag; t < n - max_lag; ++t) sum += static_cast<double>(x[t]) * x[n + t + lag];
    if (sum > best) {
      best = sum;
      best_lag = lag;
    }
  }
  return best_lag;
}

TEST(RoomScene, TheDirectPathsDelayBetweenSensorsIsTheGeometrys) {
  const RoomScene scene = OneSource(RoomSignal::kBroadband);
  const std::vector<Vec3> sensors = {Vec3(1.0, 1.0, 1.0), Vec3(1.6, 1.0, 1.0)};
  auto rendered = RenderRoomScene(scene, sensors, 3);
  ASSERT_TRUE(rendered.ok()) << rendered.status().message();
  const double delay_samples =
      ((scene.sources[0].position_m - sensors[1]).norm() - (scene.sources[0].position_m - sensors[0]).norm()) / 343.0 *
      16000.0;
  EXPECT_NEAR(MeasuredLag(rendered->samples, rendered->samples_per_channel, 40), delay_samples, 0.6);
}

TEST(RoomScene, BurstsSoundOnlyInTheirIntervalsAndASeedReplays) {
  RoomScene scene = OneSource(RoomSignal::kBursts);
  scene.duration_s = 8.0;
  const std::vector<Vec3> sensors = {Vec3(1.0, 1.0, 1.0), Vec3(1.1, 1.0, 1.0)};
  auto a = RenderRoomScene(scene, sensors, 5);
  ASSERT_TRUE(a.ok());
  ASSERT_FALSE(a->sounding.empty());
  const RoomSceneSource& s = scene.sources[0];
  double previous_end = -1.0;
  for (const SoundingInterval& i : a->sounding) {
    EXPECT_GT(i.on_s, previous_end);  // ordered, gaps between
    EXPECT_LE(i.off_s - i.on_s, s.on_max_s + 1e-9);
    previous_end = i.off_s;
  }
  // Power at sensor 0 while sounding (past the travel time and the edges) against silence.
  const double travel_s = (s.position_m - sensors[0]).norm() / 343.0;
  double on = 0.0, off = 0.0;
  int64_t on_n = 0, off_n = 0;
  for (int64_t t = 0; t < a->samples_per_channel; ++t) {
    const double emitted_s = static_cast<double>(t) / 16000.0 - travel_s;
    bool inside = false, near_edge = false;
    for (const SoundingInterval& i : a->sounding) {
      inside |= emitted_s > i.on_s + 0.02 && emitted_s < i.off_s - 0.02;
      near_edge |= std::abs(emitted_s - i.on_s) < 0.03 || std::abs(emitted_s - i.off_s) < 0.03;
    }
    const double v = a->samples[static_cast<size_t>(t)];
    if (inside) {
      on += v * v;
      ++on_n;
    } else if (!near_edge) {
      off += v * v;
      ++off_n;
    }
  }
  ASSERT_GT(on_n, 0);
  ASSERT_GT(off_n, 0);
  EXPECT_GT(10.0 * std::log10((on / static_cast<double>(on_n)) / (off / static_cast<double>(off_n))),
            20.0);  // noise 40 dB down at 1 m; the source ~3 m off
  auto again = RenderRoomScene(scene, sensors, 5);
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(again->samples, a->samples);
  auto other = RenderRoomScene(scene, sensors, 6);
  ASSERT_TRUE(other.ok());
  EXPECT_NE(other->samples, a->samples);
}

TEST(RoomScene, BadScenesAreRefusedNamingTheField) {
  const std::vector<Vec3> sensors = {Vec3(1.0, 1.0, 1.0), Vec3(1.1, 1.0, 1.0)};
  const auto refused = [&](const RoomScene& scene, const std::string& words) {
    const Status s = scene.Validate(sensors);
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
    EXPECT_NE(s.message().find(words), std::string::npos) << s.message();
  };
  RoomScene scene = OneSource(RoomSignal::kTones);
  EXPECT_TRUE(scene.Validate(sensors).ok());
  RoomScene bad = scene;
  bad.sources[0].position_m = Vec3(7.0, 1.0, 1.0);
  refused(bad, "sources[0].position_m lies outside the room");
  bad = scene;
  bad.sources[0].band_high_hz = 9000.0;
  refused(bad, "sources[0].band_hz");
  bad = scene;
  bad.sources[0].on_min_s = 0.0;
  refused(bad, "sources[0].on_s");
  bad = scene;
  bad.duration_s = 0.0;
  refused(bad, "duration_s");
  bad = scene;
  bad.sources.clear();
  refused(bad, "1 to 16 sources");
  bad = scene;
  bad.room.rt60_s = 3.0;
  refused(bad, "rt60_s");
  bad = scene;
  bad.duration_s = 600.0;
  bad.sample_rate_hz = 192000.0;
  EXPECT_NE(bad.Validate(std::vector<Vec3>(4, Vec3(1, 1, 1))).message().find("2e8 samples"), std::string::npos);
  EXPECT_NE(scene.Validate({Vec3(-1.0, 1.0, 1.0)}).message().find("sensor 0 lies outside the room"), std::string::npos);
  EXPECT_EQ(ParseRoomSignal("whisper", "signal").status().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace localizer::engine
