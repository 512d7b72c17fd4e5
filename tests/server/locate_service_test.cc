// Locate and config validation against an in-process localizer-server on a loopback port:
// - Locate on a simulated block: each TDOA within 4 sigma of the time-delay CRLB and the fix
//   within 4 x the position CRLB plus the source's motion over half the block of the truth
//   (the derivation is in the test); and the server's answer is engine::Locate's.
// - A config with 3 sensors asked for a position: INVALID_ARGUMENT naming array.sensors_m.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "clients/grpc/track_stream.h"
#include "clients/io/simulation_files.h"
#include "engine/array/multilateration.h"
#include "engine/pipeline/locate.h"
#include "localizer/v1/localizer.grpc.pb.h"
#include "tests/pipeline/scenario_run.h"
#include "tests/server/loopback_server.h"
#include "wire/block_wire.h"
#include "wire/config_wire.h"
#include "wire/status_wire.h"

namespace localizer::client {
namespace {

using LocateServiceTest = LoopbackServerTest;

// One block through Locate: the server's answer is engine::Locate's, and the fix is
// within a physical bound of the truth.
TEST_F(LocateServiceTest, LocateFixIsWithinTheCrlbBoundOfTheTruth) {
  auto run = io::SimulateScenario("tetra-water", 1, 4.0);
  ASSERT_TRUE(run.ok()) << run.status().ToString();
  const engine::SimResult& sim = run->result;
  engine::AudioSessionConfig config = engine::SessionConfigFor(run->scenario);

  // 0.25 s from t = 2 s: samples [22050, 24806) per channel.
  const int64_t start = 22050;
  const int64_t n = 2756;
  std::vector<float> block(static_cast<size_t>(n * sim.channel_count));
  for (int c = 0; c < sim.channel_count; ++c) {
    std::copy_n(sim.samples.begin() + c * sim.samples_per_channel + start, n, block.begin() + c * n);
  }
  const engine::BlockView view{1, sim.channel_count, n, block.data()};
  v1::LocateRequest request;
  *request.mutable_config() = wire::ConfigToProto(config, "");
  request.mutable_config()->set_max_block_samples(0);
  wire::EncodeBlock(view, /*pcm16=*/false, request.mutable_block());
  auto stub = v1::Localizer::NewStub(channel_);
  grpc::ClientContext context;
  v1::LocateResponse response;
  const grpc::Status status = stub->Locate(&context, request, &response);
  ASSERT_TRUE(status.ok()) << wire::FromGrpcStatus(status).ToString();
  ASSERT_TRUE(response.fix_found());
  ASSERT_EQ(response.pairs_size(), 3);

  // The server ran the engine's Locate on the same samples: same delays, same fix.
  auto local = engine::Locate(config, view);
  ASSERT_TRUE(local.ok()) << local.status().ToString();
  for (int p = 0; p < 3; ++p) {
    EXPECT_EQ(response.pairs(p).delay_s(), local->measurement.pairs[static_cast<size_t>(p)].delay_s);
  }
  EXPECT_EQ(response.position_m().x(), local->fix.position_m.x());

  // Tolerance, from the Cramér–Rao bounds. Time delay (Knapp & Carter 1976): over an
  // observation of T seconds,
  //   var(tdoa) >= 1 / (2 T integral (2 pi f)^2 gamma^2 / (1 - gamma^2) df),
  // where gamma^2 / (1 - gamma^2) = s^2 / (1 + 2 s) for an in-band signal-to-noise PSD ratio
  // s on both channels. The scenario's 20 dB SNR is over the whole band 0..fs/2 (white
  // noise) while the source fills [300, 3000] Hz, so s = 100 (fs / 2) / 2700. With T = 0.25 s
  // that gives sigma_tdoa ~ 0.24 us. Position: sqrt(trace(CRLB(sigma_tdoa))) at the true
  // position (engine::TdoaPositionCrlb). The source moves at 1 m/s, so across the block it
  // is within v T / 2 = 0.125 m of where it was at the block's centre t_c. Bounds: each
  // TDOA within 4 sigma_tdoa of the true delay at t_c; the fix within
  // 4 sqrt(trace(CRLB(sigma_tdoa))) + v T / 2 (about 0.23 m) of the true position at t_c.
  const double fs = sim.sample_rate_hz;
  const double duration_s = static_cast<double>(n) / fs;
  const double band_low_hz = run->scenario.sim.band_low_hz;
  const double band_high_hz = run->scenario.sim.band_high_hz;
  const double s = std::pow(10.0, run->scenario.sim.snr_db / 10.0) * (0.5 * fs) / (band_high_hz - band_low_hz);
  const double two_pi_sq = 4.0 * std::numbers::pi * std::numbers::pi;
  const double integral =
      two_pi_sq * (std::pow(band_high_hz, 3) - std::pow(band_low_hz, 3)) / 3.0 * (s * s / (1.0 + 2.0 * s));
  const double sigma_tdoa_s = 1.0 / std::sqrt(2.0 * duration_s * integral);
  const double t_c = (static_cast<double>(start) + 0.5 * static_cast<double>(n)) / fs;
  const engine::Vec3 truth = sim.TruthAt(t_c).position_m;
  auto array = engine::ArrayGeometry::Create(config.sensors_m, config.sound_speed_mps, 0);
  ASSERT_TRUE(array.ok());
  for (int p = 0; p < 3; ++p) {
    // Arrival at sensor k minus arrival at the reference (engine/core/measurement.h).
    const int k = array->sensor_of_pair(p);
    const double true_delay_s =
        ((truth - array->sensor_m(k)).norm() - (truth - array->sensor_m(0)).norm()) / config.sound_speed_mps;
    EXPECT_NEAR(response.pairs(p).delay_s(), true_delay_s, 4.0 * sigma_tdoa_s)
        << "pair " << p << ", sigma_tdoa_s " << sigma_tdoa_s;
  }
  const double crlb_m = std::sqrt(engine::TdoaPositionCrlb(*array, truth, sigma_tdoa_s).trace());
  const double speed_mps = run->scenario.sim.trajectory.velocity_mps.norm();  // 1 m/s, CV
  const double bound_m = 4.0 * crlb_m + speed_mps * duration_s / 2.0;
  const engine::Vec3 fix(response.position_m().x(), response.position_m().y(), response.position_m().z());
  EXPECT_LT((fix - truth).norm(), bound_m)
      << "fix " << fix.transpose() << " truth " << truth.transpose() << " crlb_m " << crlb_m;
}

// The server validates the config: 3 sensors cannot give a position, refused naming the
// proto field (they can give directions: localization auto).
TEST_F(LocateServiceTest, ThreeSensorsIsInvalidArgumentNamingTheField) {
  engine::AudioSessionConfig config;
  config.sensors_m = {engine::Vec3(0, 0, 0), engine::Vec3(1, 0, 0), engine::Vec3(0, 1, 0)};
  config.localization = engine::Localization::kPosition;
  config.sample_rate_hz = 11025.0;
  auto stream = TrackStream::Open(channel_, wire::ConfigToProto(config, "three"), "key-3");
  ASSERT_FALSE(stream.ok());
  EXPECT_EQ(stream.status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(stream.status().message().rfind("INVALID_ARGUMENT: ", 0), 0u) << stream.status().message();
  EXPECT_NE(stream.status().message().find("array.sensors_m"), std::string::npos) << stream.status().message();
}

}  // namespace
}  // namespace localizer::client
