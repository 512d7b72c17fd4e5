// /metrics after real traffic: promtool accepts it and the histograms count exactly what
// was processed. gRPC health: SERVING, then NOT_SERVING while a SIGTERM-style drain
// finishes in-flight frames, whose estimates all reach the client.
#include <grpcpp/generic/generic_stub.h>

#include <cstdio>
#include <fstream>
#include <future>
#include <regex>

#include "tests/server/http_client.h"
#include "tests/server/run_shell.h"
#include "tests/server/service_fixture.h"
#include "wire/tsan_annotations.h"

namespace localizer::server::testing {
namespace {

constexpr int64_t kBlock = 2048;

// The value of the series `name{labels}` (labels exactly as written), or -1.
double SeriesValue(const std::string& text, const std::string& series) {
  const size_t at = text.find("\n" + series + " ");
  if (at == std::string::npos) return -1.0;
  return std::stod(text.substr(at + series.size() + 2));
}

// grpc.health.v1.Health/Check for the whole server, by hand-encoded protobuf bytes:
// the request is empty; the response is field 1 (varint): 1 SERVING, 2 NOT_SERVING.
int HealthStatus(const std::shared_ptr<grpc::Channel>& channel, grpc::Status* rpc_status) {
  grpc::GenericStub stub(channel);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(2));
  grpc::Slice empty_message("");
  grpc::ByteBuffer request(&empty_message, 1), response;  // a default ByteBuffer is no message
  std::promise<grpc::Status> done;
  // The callback runs on a gRPC thread once the call completed: gRPC (not built with TSan)
  // orders it after this thread's writes, and TSan learns so here (tsan_annotations.h).
  wire::TsanRelease(&done);
  stub.UnaryCall(&context, "/grpc.health.v1.Health/Check", grpc::StubOptions(), &request, &response,
                 [&done](const grpc::Status& s) {
                   wire::TsanAcquire(&done);
                   done.set_value(s);
                 });
  *rpc_status = done.get_future().get();
  if (!rpc_status->ok()) return -1;
  std::vector<grpc::Slice> slices;
  (void)response.Dump(&slices);
  std::string bytes;
  for (const auto& s : slices) bytes.append(reinterpret_cast<const char*>(s.begin()), s.size());
  if (bytes.size() == 2 && bytes[0] == 0x08) return bytes[1];
  return bytes.empty() ? 0 : -2;  // an empty message is status 0 (UNKNOWN)
}

TEST_F(ServiceTest, MetricsCountWhatWasProcessedAndPassPromtool) {
  const Scenario s = MakeScenario("tetra-water", 3.0, 1, kBlock);
  TestStream stream(stub_.get());
  ASSERT_TRUE(stream.Send(s.OpenRequest()));
  const int64_t blocks = s.BlockCount(kBlock);
  for (int64_t k = 1; k <= blocks; ++k) ASSERT_TRUE(stream.Send(s.BlockRequest(k, kBlock)));
  v1::TrackRequest bad = s.BlockRequest(blocks, kBlock);  // a duplicate
  ASSERT_TRUE(stream.Send(bad));
  ASSERT_TRUE(stream.Close().ok());
  const double estimates = static_cast<double>(stream.estimates().size());
  ASSERT_GT(estimates, 0.0);

  const auto response = localizer::testing::Request(server_->metrics_port(), "GET", "/metrics");
  ASSERT_EQ(response.status, 200);
  const std::string& text = response.body;
  EXPECT_EQ(SeriesValue(text, "localizer_stage_seconds_count{stage=\"tdoa\",backend=\"cpu\"}"), estimates);
  EXPECT_EQ(SeriesValue(text, "localizer_stage_seconds_count{stage=\"filter\",backend=\"cpu\"}"), estimates);
  EXPECT_EQ(SeriesValue(text, "localizer_stage_seconds_count{stage=\"total\",backend=\"cpu\"}"), estimates);
  EXPECT_EQ(SeriesValue(text, "localizer_stage_seconds_count{stage=\"queue\",backend=\"cpu\"}"),
            static_cast<double>(blocks));
  EXPECT_EQ(SeriesValue(text, "localizer_stage_seconds_bucket{stage=\"tdoa\",backend=\"cpu\",le=\"+Inf\"}"), estimates);
  EXPECT_GT(SeriesValue(text, "localizer_stage_seconds_sum{stage=\"tdoa\",backend=\"cpu\"}"), 0.0);
  EXPECT_EQ(SeriesValue(text, "localizer_estimates_total{backend=\"cpu\"}"), estimates);
  EXPECT_EQ(SeriesValue(text, "localizer_blocks_total"), static_cast<double>(blocks));
  EXPECT_EQ(SeriesValue(text, "localizer_samples_total"), static_cast<double>(s.sim.samples_per_channel));
  EXPECT_EQ(SeriesValue(text, "localizer_rejections_total{reason=\"duplicate\"}"), 1.0);
  EXPECT_EQ(SeriesValue(text, "localizer_sessions_opened_total{how=\"open\"}"), 1.0);
  EXPECT_EQ(SeriesValue(text, "localizer_sessions_closed_total{reason=\"finished\"}"), 1.0);
  EXPECT_EQ(SeriesValue(text, "localizer_sessions{state=\"attached\"}"), 0.0);
  EXPECT_EQ(SeriesValue(text, "localizer_queue_depth_blocks"), 0.0);
  EXPECT_NE(text.find("localizer_build_info{version=\""), std::string::npos);

  if (localizer::testing::RunShell("command -v promtool > /dev/null 2>&1") != 0) {
    GTEST_SKIP() << "promtool not installed (Debian package prometheus); text checks above passed";
  }
  const std::string path = ::testing::TempDir() + "/service_metrics.txt";
  std::ofstream(path) << text;
  const std::string command = "promtool check metrics < " + path + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string output;
  char buffer[512];
  while (fgets(buffer, sizeof buffer, pipe) != nullptr) output += buffer;
  EXPECT_EQ(pclose(pipe), 0) << output;
  EXPECT_EQ(output, "") << "promtool lint: " << output;
}

// The drain must end because the frames are done, not because it timed out: under TSan (-O1,
// several times slower) the 193 frames of 65536 particles below took longer than the default
// 10 s on two shared cores.
class DrainTest : public ServiceTest {
 protected:
  void SetUp() override {
    ServerOptions options;
    options.drain_timeout_s = 600.0;
    StartServer(options);
  }
};

TEST_F(DrainTest, HealthFlipsDuringDrainAndInFlightFramesFinish) {
  grpc::Status rpc;
  ASSERT_EQ(HealthStatus(channel_, &rpc), 1) << rpc.error_message();

  // A heavy session (many frames per block, many particles) so the drain takes a while.
  Scenario s = MakeScenario("tetra-water", 2.0, 1, kBlock);
  v1::TrackRequest open = s.OpenRequest();
  open.mutable_open()->set_hop_samples(64);
  open.mutable_open()->mutable_filter()->set_particles(65536);
  TestStream stream(stub_.get());
  ASSERT_TRUE(stream.Send(open));
  for (int64_t k = 1; k <= 8; ++k) ASSERT_TRUE(stream.Send(s.BlockRequest(k, kBlock)));
  ASSERT_TRUE(stream.WaitForEstimates(1));

  auto shutdown = std::async(std::launch::async, [this] { server_->Shutdown(); });
  bool saw_not_serving = false;
  while (shutdown.wait_for(std::chrono::milliseconds(5)) != std::future_status::ready) {
    if (HealthStatus(channel_, &rpc) == 2) saw_not_serving = true;
  }
  EXPECT_TRUE(saw_not_serving) << "health never reported NOT_SERVING during the drain";
  const grpc::Status status = stream.Finish();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::UNAVAILABLE) << status.error_message();
  // Every frame of every accepted block was delivered: 8 blocks of 2048 with hop 64 and
  // frame 4096 make (8 * 2048 - 4096) / 64 + 1 frames.
  EXPECT_EQ(stream.estimates().size(), static_cast<size_t>((8 * kBlock - 4096) / 64 + 1));
  EXPECT_EQ(stream.estimates().back().sequence(), 8u);
}

}  // namespace
}  // namespace localizer::server::testing
