// A client that sends faster than the server works is held back by HTTP/2 flow control:
// the server stops reading a session whose queue is full, so its memory stays bounded
// and the client's writes stall; nothing is dropped, and reading again lets it finish.
#include <atomic>

#include "tests/server/http_client.h"
#include "tests/server/service_fixture.h"

namespace localizer::server::testing {
namespace {

constexpr int kBlocks = 400;  // 100 MiB in all: far more than any transport buffer holds

double QueueDepth(int metrics_port) {
  const auto response = localizer::testing::Request(metrics_port, "GET", "/metrics");
  const size_t at = response.body.find("\nlocalizer_queue_depth_blocks ");
  return at == std::string::npos ? -1.0 : std::stod(response.body.substr(at + 30));
}

class BackpressureTest : public ServiceTest {
 protected:
  void SetUp() override {
    ServerOptions options;
    options.max_queued_requests = 2;
    StartServer(options);
  }
};

TEST_F(BackpressureTest, FullQueueStallsTheClientInsteadOfGrowingMemory) {
  // One 1.5 s block (16537 samples per channel, 258 KiB of float32), sent again and again.
  Scenario s = MakeScenario("tetra-water", 1.5, 1, 2048);
  const int64_t block_samples = s.sim.samples_per_channel;
  const v1::TrackRequest block = s.BlockRequest(1, block_samples);
  v1::TrackRequest open = s.OpenRequest();
  open.mutable_open()->set_hop_samples(256);  // 65 frames per block: slow on purpose

  grpc::ClientContext context;
  auto stream = stub_->Track(&context);
  ASSERT_TRUE(stream->Write(open));
  v1::TrackResponse opened;
  ASSERT_TRUE(stream->Read(&opened));
  ASSERT_TRUE(opened.has_opened());

  // Write without reading any response: the outbox fills, processing stops, the queue
  // fills, reading stops, and the transport's windows fill.
  std::atomic<int> written{0};
  std::thread writer([&] {
    for (int k = 1; k <= kBlocks; ++k) {
      v1::TrackRequest request = block;
      request.mutable_block()->set_sequence(static_cast<uint64_t>(k));
      if (!stream->Write(request)) return;
      written = k;
    }
    stream->WritesDone();
  });
  int stalled_at = -1;
  double max_depth = 0.0;
  for (int i = 0; i < 60; ++i) {  // up to 6 s for the writes to stall
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    max_depth = std::max(max_depth, QueueDepth(server_->metrics_port()));
    const int now = written;
    if (now == stalled_at) break;
    stalled_at = now;
  }
  std::printf("writes stalled after %d of %d blocks; largest queue depth seen %.0f\n", stalled_at, kBlocks, max_depth);
  EXPECT_LT(stalled_at, kBlocks / 2) << "the client was never held back";
  EXPECT_LE(max_depth, 2.0) << "the server queued more than --max-queue-blocks";

  // Reading again drains everything: every block is processed, nothing was dropped.
  v1::TrackResponse response;
  uint64_t estimates = 0, rejected = 0;
  while (stream->Read(&response)) {
    estimates += response.has_estimate() ? 1 : 0;
    rejected += response.has_rejected() ? 1 : 0;
  }
  writer.join();
  EXPECT_TRUE(stream->Finish().ok());
  EXPECT_EQ(rejected, 0u);
  EXPECT_EQ(estimates, static_cast<uint64_t>((kBlocks * block_samples - 4096) / 256 + 1));
}

}  // namespace
}  // namespace localizer::server::testing
