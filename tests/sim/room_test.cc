#include "engine/sim/room.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>

namespace localizer::engine {
namespace {

constexpr double kFs = 16000.0;

// The largest |h| within 2 samples of a delay, and its fractional position.
double PeakNear(const std::vector<double>& h, double delay_samples, double* at = nullptr) {
  const auto centre = static_cast<long>(std::lround(delay_samples));
  double best = 0.0;
  for (long n = centre - 2; n <= centre + 2; ++n) {
    if (n < 0 || n >= static_cast<long>(h.size())) continue;
    if (std::abs(h[static_cast<size_t>(n)]) > std::abs(best)) {
      best = h[static_cast<size_t>(n)];
      if (at) *at = static_cast<double>(n);
    }
  }
  return best;
}

TEST(Room, TheDirectPathArrivesAtDistanceOverSpeedWithSphericalSpreading) {
  ShoeboxRoom room;
  room.rt60_s = 0.0;  // anechoic
  const Vec3 source(1.0, 1.0, 1.5), sensor(4.0, 3.0, 1.2);
  auto h = RoomImpulseResponses(room, source, {sensor}, kFs);
  ASSERT_TRUE(h.ok()) << h.status().ToString();
  const double d = (sensor - source).norm();
  // An integer delay makes the band-limited impulse a single tap of 1 / (4 pi d).
  const double c = d * kFs / std::round(d / room.sound_speed_mps * kFs);
  room.sound_speed_mps = c;
  h = RoomImpulseResponses(room, source, {sensor}, kFs);
  ASSERT_TRUE(h.ok());
  double at = 0.0;
  EXPECT_NEAR(PeakNear((*h)[0], d / c * kFs, &at), 1.0 / (4.0 * std::numbers::pi * d), 1e-9);
  EXPECT_DOUBLE_EQ(at, std::round(d / c * kFs));
  double elsewhere = 0.0;  // nothing but the direct path
  for (size_t n = 0; n < (*h)[0].size(); ++n)
    if (std::abs(static_cast<double>(n) - at) > 0.5) elsewhere = std::max(elsewhere, std::abs((*h)[0][n]));
  EXPECT_LT(elsewhere, 1e-12);
}

TEST(Room, TheFloorReflectionArrivesFromTheMirrorImageScaledByBeta) {
  ShoeboxRoom room;
  room.rt60_s = 0.4;
  const Vec3 source(2.0, 2.5, 1.5), sensor(3.0, 2.5, 1.0);
  auto h = RoomImpulseResponses(room, source, {sensor}, kFs);
  ASSERT_TRUE(h.ok());
  const double beta = std::sqrt(1.0 - room.WallAbsorption());
  const Vec3 floor_image(2.0, 2.5, -1.5);
  const double d = (sensor - floor_image).norm();  // 2.69 m; the next image (ceiling) at 3.64 m
  // A band-limited impulse at a fractional delay peaks at its nearest sample, at the amplitude
  // times sinc(that sample's offset); the high-pass and the other images' tails move it a little.
  const double at = d / room.sound_speed_mps * kFs, offset = at - std::round(at);
  const double sinc =
      std::abs(offset) < 1e-12 ? 1.0 : std::sin(std::numbers::pi * offset) / (std::numbers::pi * offset);
  const double expected = beta / (4.0 * std::numbers::pi * d) * sinc;
  EXPECT_NEAR(PeakNear((*h)[0], at), expected, 0.1 * expected);
  EXPECT_GT(beta, 0.0);
  EXPECT_LT(beta, 1.0);
}

TEST(Room, EnergyDecaysAtTheRequestedReverberationTime) {
  // Schroeder's backward integral of h^2; the decay from -5 to -25 dB, times 3 (T20).
  for (const double rt60_s : {0.2, 0.4, 0.6}) {
    ShoeboxRoom room;
    room.rt60_s = rt60_s;
    auto h = RoomImpulseResponses(room, Vec3(1.3, 1.7, 1.1), {Vec3(4.1, 3.2, 1.6)}, kFs, 1.2 * rt60_s);
    ASSERT_TRUE(h.ok());
    const std::vector<double>& r = (*h)[0];
    std::vector<double> tail(r.size() + 1, 0.0);
    for (size_t n = r.size(); n-- > 0;) tail[n] = tail[n + 1] + r[n] * r[n];
    auto crossing = [&](double db) {
      for (size_t n = 0; n < r.size(); ++n)
        if (10.0 * std::log10(tail[n] / tail[0]) <= db) return static_cast<double>(n) / kFs;
      return std::numeric_limits<double>::quiet_NaN();
    };
    const double t20 = 3.0 * (crossing(-25.0) - crossing(-5.0));
    EXPECT_NEAR(t20, rt60_s, 0.2 * rt60_s) << "RT60 " << rt60_s;
  }
}

TEST(Room, RenderingIsTheSignalThroughTheImpulseResponse) {
  ShoeboxRoom room;
  room.rt60_s = 0.15;
  const std::vector<Vec3> sensors{Vec3(3.0, 2.0, 1.0), Vec3(3.1, 2.0, 1.0)};
  std::mt19937_64 rng(3);
  std::normal_distribution<double> normal;
  RoomSource source;
  source.position_m = Vec3(1.0, 3.0, 1.5);
  for (int i = 0; i < 4000; ++i) source.signal.push_back(normal(rng));
  auto rendered = RenderInRoom(room, {source}, sensors, kFs, 6000);
  ASSERT_TRUE(rendered.ok());
  auto h = RoomImpulseResponses(room, source.position_m, sensors, kFs);
  ASSERT_TRUE(h.ok());
  for (size_t m = 0; m < sensors.size(); ++m) {
    for (int t : {100, 1234, 3999, 5999}) {  // direct convolution at a few instants
      double expected = 0.0;
      for (int k = 0; k <= t && k < static_cast<int>((*h)[m].size()); ++k)
        if (t - k < 4000) expected += (*h)[m][static_cast<size_t>(k)] * source.signal[static_cast<size_t>(t - k)];
      EXPECT_NEAR((*rendered)[m * 6000 + static_cast<size_t>(t)], expected, 1e-4 + 1e-4 * std::abs(expected))
          << m << " " << t;
    }
  }
}

TEST(Room, PositionsOutsideTheRoomAreNamed) {
  ShoeboxRoom room;
  EXPECT_EQ(RoomImpulseResponses(room, Vec3(7.0, 1.0, 1.0), {Vec3(1, 1, 1)}, kFs).status().code(),
            StatusCode::kInvalidArgument);
  const Status sensor = RoomImpulseResponses(room, Vec3(1, 1, 1), {Vec3(1, 2, 1), Vec3(1, 1, -0.1)}, kFs).status();
  EXPECT_NE(sensor.message().find("sensor 1"), std::string::npos) << sensor.message();
  room.rt60_s = -1.0;
  EXPECT_NE(room.Validate().message().find("rt60_s"), std::string::npos);
}

}  // namespace
}  // namespace localizer::engine
