// Moving arrays over the wire: a session opened with SessionConfig.platform takes ImuBatch
// requests in order with its blocks and answers exactly what the engine gives offline for
// the same samples, each estimate carrying the platform pose; a bad batch is refused in-band
// (request "imu") and the session goes on; a fixed-array session refuses IMU batches.
#include <cmath>
#include <nlohmann/json.hpp>

#include "engine/sim/platform_motion.h"
#include "tests/server/http_client.h"
#include "tests/server/service_fixture.h"
#include "wire/imu_wire.h"

namespace localizer::server::testing {
namespace {

constexpr int64_t kBlock = 2048;
constexpr double kImuRateHz = 100.0;

// tetra-water on a yawing, rolling buoy for 4 s, its IMU, and the offline run that takes
// each block's IMU samples (those up to the block's end) before the block.
struct MovingScenario {
  Scenario base;
  std::vector<engine::ImuSample> imu;
  std::vector<std::vector<engine::ImuSample>> imu_per_block;  // [k - 1]
};

MovingScenario MakeMoving() {
  MovingScenario m;
  engine::Scenario scenario = *engine::MakeScenario("tetra-water", 4);
  scenario.sim.duration_s = 4.0;
  engine::AttitudeTrajectoryOptions motion;
  motion.euler_rate_rps = engine::Vec3(0.0, 0.0, 0.3);
  motion.amplitude_rad = engine::Vec3(0.15, 0.0, 0.0);
  motion.frequency_hz = engine::Vec3(0.25, 0.0, 0.0);
  scenario.sim.platform_attitude = motion;
  const auto array = *engine::ArrayGeometry::Create(scenario.sensors_m, scenario.sound_speed_mps);
  m.base.sim = *engine::Simulate(array, scenario.sim);
  m.base.config = engine::SessionConfigFor(scenario);
  m.base.config.tracker.particle.particles = 1024;
  m.base.config.seed = 4;
  m.base.config.backend = engine::BackendChoice::kCpu;
  m.base.config.array_in_body_frame = true;
  engine::ImuNoise noise;
  noise.gyro_noise_sd_rps = 0.002;
  noise.accel_noise_sd_mps2 = 0.03;
  m.imu = engine::SynthesiseImu(engine::AttitudeTrajectory(motion), kImuRateHz, 4.0, noise, 9);
  auto session = std::move(*engine::Session::Create(m.base.config));
  size_t next = 0;
  for (int64_t k = 1; k <= m.base.BlockCount(kBlock); ++k) {
    const double end_s = static_cast<double>(k * kBlock) / m.base.sim.sample_rate_hz;
    std::vector<engine::ImuSample> batch;
    while (next < m.imu.size() && m.imu[next].t_s <= end_s) batch.push_back(m.imu[next++]);
    EXPECT_TRUE(session->AddImu(batch).ok());
    m.imu_per_block.push_back(batch);
    const std::vector<float> b = m.base.Block(k, kBlock);
    EXPECT_TRUE(session
                    ->Process({static_cast<uint64_t>(k), m.base.sim.channel_count,
                               static_cast<int64_t>(b.size()) / m.base.sim.channel_count, b.data()},
                              &m.base.offline)
                    .ok());
  }
  return m;
}

v1::TrackRequest ImuRequest(const std::vector<engine::ImuSample>& samples, uint64_t sequence) {
  v1::TrackRequest request;
  wire::EncodeImuBatch(samples, nullptr, sequence, request.mutable_imu());
  return request;
}

class MovingArrayServiceTest : public ServiceTest {
 protected:
  MovingScenario moving_ = MakeMoving();
};

TEST_F(MovingArrayServiceTest, StreamEqualsTheOfflineRunAndCarriesThePose) {
  TestStream stream(stub_.get());
  ASSERT_TRUE(stream.Send(moving_.base.OpenRequest()));
  for (int64_t k = 1; k <= moving_.base.BlockCount(kBlock); ++k) {
    ASSERT_TRUE(stream.Send(ImuRequest(moving_.imu_per_block[static_cast<size_t>(k - 1)], static_cast<uint64_t>(k))));
    ASSERT_TRUE(stream.Send(moving_.base.BlockRequest(k, kBlock)));
  }
  ASSERT_TRUE(stream.Close().ok());
  EXPECT_TRUE(stream.opened().effective_config().has_platform());
  EXPECT_EQ(stream.opened().effective_config().platform().attitude_filter(), "quaternion");
  const std::vector<v1::Estimate> got = stream.estimates();
  ASSERT_EQ(got.size(), moving_.base.offline.size());
  ASSERT_GT(got.size(), 10u);
  for (size_t i = 0; i < got.size(); ++i) {
    const engine::Estimate& want = moving_.base.offline[i];
    ExpectSameEstimate(want, got[i]);
    ASSERT_TRUE(want.platform.has_value());
    ASSERT_TRUE(got[i].has_platform());
    EXPECT_EQ(got[i].platform().body_to_world().w(), want.platform->body_to_world.w());
    EXPECT_EQ(got[i].platform().body_to_world().z(), want.platform->body_to_world.z());
    EXPECT_EQ(got[i].platform().euler_rad().z(), want.platform->euler_rad.z());
  }
  // The yaw reported follows the buoy's 0.3 rad/s turn (yaw starts at 0: no magnetometer).
  const v1::Estimate& last = got.back();
  EXPECT_NEAR(last.platform().euler_rad().z(), 0.3 * last.t_s(), 0.05);
}

TEST_F(MovingArrayServiceTest, LiveViewDrawsTheSensorsWhereThePoseMovedThem) {
  TestStream stream(stub_.get());
  ASSERT_TRUE(stream.Send(moving_.base.OpenRequest()));
  for (int64_t k = 1; k <= moving_.base.BlockCount(kBlock); ++k) {
    ASSERT_TRUE(stream.Send(ImuRequest(moving_.imu_per_block[static_cast<size_t>(k - 1)], static_cast<uint64_t>(k))));
    ASSERT_TRUE(stream.Send(moving_.base.BlockRequest(k, kBlock)));
  }
  ASSERT_TRUE(stream.WaitForEstimates(moving_.base.offline.size()));
  const auto response = localizer::testing::Request(server_->metrics_port(), "GET", "/sessions");
  ASSERT_EQ(response.status, 200);
  const nlohmann::json doc = nlohmann::json::parse(response.body);
  const auto& session = doc.at("sessions")[0];
  const engine::PlatformAttitude& pose = *moving_.base.offline.back().platform;
  ASSERT_TRUE(session.contains("platform"));
  EXPECT_DOUBLE_EQ(session.at("platform").at("body_to_world_wxyz")[0].get<double>(), pose.body_to_world.w());
  const engine::Vec3 moved = pose.body_to_world * moving_.base.config.sensors_m[1] + pose.origin_m;
  EXPECT_NEAR(session.at("sensors_m")[1][0].get<double>(), moved.x(), 1e-12);
  EXPECT_NEAR(session.at("sensors_m")[1][1].get<double>(), moved.y(), 1e-12);
  EXPECT_EQ(session.at("kind"), "samples");
  ASSERT_TRUE(stream.Close().ok());
}

TEST_F(MovingArrayServiceTest, BadImuBatchIsRefusedInBandAndTheSessionGoesOn) {
  TestStream stream(stub_.get());
  ASSERT_TRUE(stream.Send(moving_.base.OpenRequest()));
  const int64_t blocks = moving_.base.BlockCount(kBlock);
  for (int64_t k = 1; k <= blocks; ++k) {
    const auto& batch = moving_.imu_per_block[static_cast<size_t>(k - 1)];
    if (k == 5) {
      v1::TrackRequest bad = ImuRequest(batch, 500);
      bad.mutable_imu()->mutable_samples(1)->mutable_gyro_rps()->set_y(std::nan(""));
      ASSERT_TRUE(stream.Send(bad));
      // The same samples again, clean: accepted (the bad batch consumed nothing).
    }
    ASSERT_TRUE(stream.Send(ImuRequest(batch, static_cast<uint64_t>(k))));
    ASSERT_TRUE(stream.Send(moving_.base.BlockRequest(k, kBlock)));
  }
  ASSERT_TRUE(stream.Close().ok());
  int rejections = 0;
  for (const auto& r : stream.responses()) {
    if (!r.has_rejected()) continue;
    ++rejections;
    EXPECT_EQ(r.rejected().request(), "imu");
    EXPECT_EQ(r.rejected().reason(), "imu");
    EXPECT_EQ(r.rejected().code(), "INVALID_ARGUMENT");
    EXPECT_EQ(r.rejected().sequence(), 500u);
    EXPECT_NE(r.rejected().message().find("imu.samples[1].gyro_rps"), std::string::npos) << r.rejected().message();
  }
  EXPECT_EQ(rejections, 1);
  // Every estimate as if the bad batch had never been sent.
  const std::vector<v1::Estimate> got = stream.estimates();
  ASSERT_EQ(got.size(), moving_.base.offline.size());
  for (size_t i = 0; i < got.size(); ++i) ExpectSameEstimate(moving_.base.offline[i], got[i]);
}

TEST_F(MovingArrayServiceTest, OutOfOrderBatchIsRefusedByTheSession) {
  TestStream stream(stub_.get());
  ASSERT_TRUE(stream.Send(moving_.base.OpenRequest()));
  ASSERT_TRUE(stream.Send(ImuRequest(moving_.imu_per_block[1], 2)));
  ASSERT_TRUE(stream.Send(ImuRequest(moving_.imu_per_block[0], 1)));  // earlier samples
  ASSERT_TRUE(stream.Send(moving_.base.BlockRequest(1, kBlock)));
  ASSERT_TRUE(stream.Close().ok());
  int rejections = 0;
  for (const auto& r : stream.responses()) {
    if (!r.has_rejected()) continue;
    ++rejections;
    EXPECT_EQ(r.rejected().sequence(), 1u);
    EXPECT_EQ(r.rejected().code(), "INVALID_ARGUMENT");
  }
  EXPECT_EQ(rejections, 1);
}

TEST_F(MovingArrayServiceTest, FixedArraySessionRefusesImu) {
  Scenario fixed = moving_.base;
  fixed.config.array_in_body_frame = false;
  TestStream stream(stub_.get());
  ASSERT_TRUE(stream.Send(fixed.OpenRequest()));
  ASSERT_TRUE(stream.Send(ImuRequest(moving_.imu_per_block[0], 7)));
  ASSERT_TRUE(stream.Send(fixed.BlockRequest(1, kBlock)));
  ASSERT_TRUE(stream.Send(fixed.BlockRequest(2, kBlock)));
  ASSERT_TRUE(stream.Close().ok());
  EXPECT_FALSE(stream.opened().effective_config().has_platform());
  int rejections = 0;
  for (const auto& r : stream.responses()) {
    if (!r.has_rejected()) continue;
    ++rejections;
    EXPECT_EQ(r.rejected().reason(), "not_moving");
    EXPECT_EQ(r.rejected().code(), "FAILED_PRECONDITION");
    EXPECT_EQ(r.rejected().request(), "imu");
  }
  EXPECT_EQ(rejections, 1);
  EXPECT_EQ(stream.estimates().size(), 1u);  // 2 x 2048 samples: one 4096 frame
}

TEST(ImuWire, DecodeNamesTheFieldAndRoundTrips) {
  engine::ImuSample a;
  a.t_s = 0.5;
  a.gyro_rps = engine::Vec3(0.1, -0.2, 0.3);
  a.accel_mps2 = engine::Vec3(0.0, 0.1, 9.8);
  engine::ImuSample b = a;
  b.t_s = 0.51;
  b.mag_uT = engine::Vec3(20.0, 0.0, -40.0);
  const engine::Vec3 origin(1.0, 2.0, 3.0);
  v1::ImuBatch batch;
  wire::EncodeImuBatch({a, b}, &origin, 3, &batch);
  auto decoded = wire::DecodeImuBatch(batch);
  ASSERT_TRUE(decoded.ok()) << decoded.status().ToString();
  ASSERT_EQ(decoded->samples.size(), 2u);
  EXPECT_EQ(decoded->samples[1].gyro_rps, b.gyro_rps);
  EXPECT_FALSE(decoded->samples[0].mag_uT.allFinite());  // no reading
  EXPECT_EQ(decoded->samples[1].mag_uT, b.mag_uT);
  EXPECT_EQ(*decoded->origin_m, origin);
  v1::ImuBatch backwards = batch;
  backwards.mutable_samples(1)->set_t_s(0.4);
  EXPECT_NE(wire::DecodeImuBatch(backwards).status().message().find("imu.samples[1].t_s"), std::string::npos);
  v1::ImuBatch no_accel = batch;
  no_accel.mutable_samples(0)->clear_accel_mps2();
  EXPECT_NE(wire::DecodeImuBatch(no_accel).status().message().find("imu.samples[0].accel_mps2"), std::string::npos);
  EXPECT_EQ(wire::DecodeImuBatch(v1::ImuBatch()).status().code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace localizer::server::testing
