// An in-process localizer server on an ephemeral loopback port, a simulated scenario to
// stream through it, and a synchronous test client for one Track stream.
#pragma once

#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <cmath>

#include <chrono>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "engine/pipeline/session.h"
#include "engine/sim/simulator.h"
#include "localizer/v1/localizer.grpc.pb.h"
#include "server/service/server.h"
#include "tests/pipeline/scenario_run.h"
#include "wire/block_wire.h"
#include "wire/config_wire.h"

namespace localizer::server::testing {

// A scenario simulated once, its engine config, and what the engine gives offline.
struct Scenario {
  engine::AudioSessionConfig config;
  engine::SimResult sim;
  std::vector<engine::Estimate> offline;  // the whole run in blocks of block_samples

  // Block k (1-based sequence k) of `block_samples` per channel, channel-major.
  std::vector<float> Block(int64_t k, int64_t block_samples) const {
    const int64_t start = (k - 1) * block_samples;
    const int64_t n = std::min(block_samples, sim.samples_per_channel - start);
    std::vector<float> out(static_cast<size_t>(n * sim.channel_count));
    for (int c = 0; c < sim.channel_count; ++c) {
      std::copy_n(sim.samples.begin() + c * sim.samples_per_channel + start, n, out.begin() + c * n);
    }
    return out;
  }
  int64_t BlockCount(int64_t block_samples) const {
    return (sim.samples_per_channel + block_samples - 1) / block_samples;
  }
  v1::TrackRequest BlockRequest(int64_t k, int64_t block_samples, bool pcm16 = false) const {
    const std::vector<float> samples = Block(k, block_samples);
    engine::BlockView view{static_cast<uint64_t>(k), sim.channel_count,
                           static_cast<int64_t>(samples.size()) / sim.channel_count, samples.data()};
    v1::TrackRequest request;
    wire::EncodeBlock(view, pcm16, request.mutable_block());
    return request;
  }
  v1::TrackRequest OpenRequest() const {
    v1::TrackRequest request;
    *request.mutable_open() = wire::ConfigToProto(config, "test");
    return request;
  }
};

// `name` simulated for `duration_s` with `seed`, tracked offline in blocks.
inline Scenario MakeScenario(const std::string& name, double duration_s, uint64_t seed, int64_t block_samples,
                             int particles = 1024) {
  Scenario s;
  engine::Scenario scenario = *engine::MakeScenario(name, seed);
  scenario.sim.duration_s = duration_s;
  const auto array = *engine::ArrayGeometry::Create(scenario.sensors_m, scenario.sound_speed_mps);
  s.sim = *engine::Simulate(array, scenario.sim);
  s.config = engine::SessionConfigFor(scenario);
  s.config.tracker.particle.particles = particles;
  s.config.seed = seed;
  s.config.backend = engine::BackendChoice::kCpu;
  auto session = std::move(*engine::Session::Create(s.config));
  for (int64_t k = 1; k <= s.BlockCount(block_samples); ++k) {
    const std::vector<float> b = s.Block(k, block_samples);
    const engine::BlockView view{static_cast<uint64_t>(k), s.sim.channel_count,
                                 static_cast<int64_t>(b.size()) / s.sim.channel_count, b.data()};
    EXPECT_TRUE(session->Process(view, &s.offline).ok());
  }
  return s;
}

// One Track stream read on a thread of its own.
class TestStream {
 public:
  explicit TestStream(v1::Localizer::Stub* stub) {
    context_.AddMetadata("x-localizer-session-key", "test");
    stream_ = stub->Track(&context_);
    reader_ = std::thread([this] {
      v1::TrackResponse response;
      while (stream_->Read(&response)) {
        std::lock_guard<std::mutex> lock(mutex_);
        responses_.push_back(response);
        changed_.notify_all();
      }
      std::lock_guard<std::mutex> lock(mutex_);
      read_done_ = true;
      changed_.notify_all();
    });
  }
  ~TestStream() {
    if (!finished_) Cancel();
  }

  bool Send(const v1::TrackRequest& request) { return stream_->Write(request); }

  // Waits until `done(responses)` holds or the stream ends; false on timeout.
  bool WaitFor(const std::function<bool(const std::vector<v1::TrackResponse>&)>& done, double timeout_s = 30.0) {
    std::unique_lock<std::mutex> lock(mutex_);
    return changed_.wait_for(lock, std::chrono::duration<double>(timeout_s), [&] {
      return done(responses_) || read_done_;
    }) && done(responses_);
  }
  bool WaitForEstimates(size_t n, double timeout_s = 30.0) {
    return WaitFor([n](const auto& r) { return CountEstimates(r) >= n; }, timeout_s);
  }

  // Half-close, read everything, return the final status.
  grpc::Status Close() {
    stream_->WritesDone();
    return Finish();
  }
  grpc::Status Cancel() {
    context_.TryCancel();
    return Finish();
  }
  grpc::Status Finish() {
    if (reader_.joinable()) reader_.join();
    if (!finished_) status_ = stream_->Finish();
    finished_ = true;
    return status_;
  }

  std::vector<v1::TrackResponse> responses() {
    std::lock_guard<std::mutex> lock(mutex_);
    return responses_;
  }
  std::vector<v1::Estimate> estimates() {
    std::vector<v1::Estimate> out;
    for (const auto& r : responses()) {
      if (r.has_estimate()) out.push_back(r.estimate());
    }
    return out;
  }
  v1::SessionOpened opened() {
    for (const auto& r : responses()) {
      if (r.has_opened()) return r.opened();
    }
    return {};
  }

  static size_t CountEstimates(const std::vector<v1::TrackResponse>& rs) {
    size_t n = 0;
    for (const auto& r : rs) n += r.has_estimate() ? 1 : 0;
    return n;
  }

 private:
  grpc::ClientContext context_;
  std::unique_ptr<grpc::ClientReaderWriter<v1::TrackRequest, v1::TrackResponse>> stream_;
  std::thread reader_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::vector<v1::TrackResponse> responses_;
  bool read_done_ = false;
  bool finished_ = false;
  grpc::Status status_;
};

class ServiceTest : public ::testing::Test {
 protected:
  void StartServer(ServerOptions options = {}) {
    options.listen = "127.0.0.1:0";
    options.metrics_listen = "127.0.0.1:0";
    if (options.workers == 0) options.workers = 2;
    options.log_level = "warn";
    auto server = Server::Start(options);
    ASSERT_TRUE(server.ok()) << server.status().ToString();
    server_ = std::move(server).value();
    channel_ =
        grpc::CreateChannel("127.0.0.1:" + std::to_string(server_->grpc_port()), grpc::InsecureChannelCredentials());
    stub_ = v1::Localizer::NewStub(channel_);
  }
  void SetUp() override { StartServer(); }
  void TearDown() override {
    if (server_) server_->Shutdown();
  }

  std::unique_ptr<Server> server_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::Localizer::Stub> stub_;
};

// Engine and wire estimates agree in everything but the timings.
inline void ExpectSameEstimate(const engine::Estimate& want, const v1::Estimate& got) {
  EXPECT_EQ(got.frame_index(), want.frame_index);
  EXPECT_EQ(got.sequence(), want.sequence);
  EXPECT_EQ(got.t_s(), want.t_s);
  EXPECT_EQ(got.initialised(), want.initialised);
  EXPECT_EQ(got.position_m().x(), want.state(0));
  EXPECT_EQ(got.position_m().y(), want.state(1));
  EXPECT_EQ(got.position_m().z(), want.state(2));
  EXPECT_EQ(got.velocity_mps().x(), want.state(3));
  EXPECT_EQ(got.velocity_mps().z(), want.state(5));
  ASSERT_EQ(got.covariance_size(), 36);
  for (int i = 0; i < 36; ++i) EXPECT_EQ(got.covariance(i), want.covariance(i / 6, i % 6));
  EXPECT_EQ(got.ess(), want.ess);
  EXPECT_EQ(got.source_present(), want.source_present);
  EXPECT_EQ(got.presence_statistic(), want.presence_statistic);
  EXPECT_EQ(got.far_field(), want.far_field);
  EXPECT_EQ(got.range_sd_m(), want.range_sd_m);
  ASSERT_EQ(static_cast<size_t>(got.pairs_size()), want.delay_s.size());
  for (int p = 0; p < got.pairs_size(); ++p) EXPECT_EQ(got.pairs(p).delay_s(), want.delay_s[static_cast<size_t>(p)]);
  // Direction sessions: every source, bit for bit.
  ASSERT_EQ(static_cast<size_t>(got.sources_size()), want.sources.size()) << "frame " << want.frame_index;
  for (int k = 0; k < got.sources_size(); ++k) {
    const v1::SourceDirection& g = got.sources(k);
    const engine::SourceEstimate& w = want.sources[static_cast<size_t>(k)];
    // The same number, or both NaN (what the array cannot observe).
    const auto same = [](double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); };
    EXPECT_EQ(g.source_id(), w.source_id);
    EXPECT_TRUE(same(g.direction().x(), w.direction.x()));
    EXPECT_TRUE(same(g.direction().z(), w.direction.z()));
    EXPECT_TRUE(same(g.azimuth_rad(), w.azimuth_rad));
    EXPECT_TRUE(same(g.elevation_rad(), w.elevation_rad));
    EXPECT_TRUE(same(g.cone_angle_rad(), w.cone_angle_rad));
    EXPECT_EQ(g.sigma_rad(), w.sigma_rad);
    EXPECT_EQ(g.source_present(), w.source_present);
    // Positions from planar and linear arrays: set exactly where the engine bounded the range.
    EXPECT_EQ(g.has_position_m(), w.position_m.allFinite());
    if (g.has_position_m()) {
      EXPECT_EQ(g.position_m().x(), w.position_m.x());
      EXPECT_EQ(g.position_m().y(), w.position_m.y());
      EXPECT_EQ(g.position_m().z(), w.position_m.z());
    }
    EXPECT_TRUE(same(g.range_sd_m(), w.range_sd_m));
  }
}

}  // namespace localizer::server::testing
