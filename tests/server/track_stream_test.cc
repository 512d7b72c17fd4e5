// A session streamed through the service gives exactly what the engine gives offline,
// also once its estimates are reused past the resume history, concurrent sessions do not
// disturb each other, and a finished stream closes its session.
#include <cmath>

#include "server/service/outbox.h"
#include "tests/server/service_fixture.h"

namespace localizer::server::testing {
namespace {

constexpr int64_t kBlock = 2048;

// Opens `s` on `stream`, sends every block and half-closes; the stream must end OK.
void StreamWhole(const Scenario& s, TestStream* stream) {
  ASSERT_TRUE(stream->Send(s.OpenRequest()));
  for (int64_t k = 1; k <= s.BlockCount(kBlock); ++k) ASSERT_TRUE(stream->Send(s.BlockRequest(k, kBlock)));
  const grpc::Status status = stream->Close();
  ASSERT_TRUE(status.ok()) << status.error_message();
}

// Every streamed estimate is the offline run's, from the CPU backend.
void ExpectOfflineEstimates(const Scenario& s, const std::vector<v1::Estimate>& estimates) {
  ASSERT_EQ(estimates.size(), s.offline.size());
  for (size_t i = 0; i < estimates.size(); ++i) {
    SCOPED_TRACE(i);
    ExpectSameEstimate(s.offline[i], estimates[i]);
    EXPECT_EQ(estimates[i].backend(), "cpu");
  }
}

TEST_F(ServiceTest, StreamedScenarioEqualsOfflineTracking) {
  const Scenario s = MakeScenario("tetra-water", 4.0, 1, kBlock);
  ASSERT_GT(s.offline.size(), 10u);
  TestStream stream(stub_.get());
  ASSERT_NO_FATAL_FAILURE(StreamWhole(s, &stream));

  const auto responses = stream.responses();
  ASSERT_FALSE(responses.empty());
  ASSERT_TRUE(responses.front().has_opened());
  const v1::SessionOpened& opened = responses.front().opened();
  EXPECT_EQ(opened.session_id().size(), 16u);
  EXPECT_EQ(opened.resume_token().size(), 32u);
  EXPECT_EQ(opened.backend(), "cpu");
  EXPECT_EQ(opened.session_ttl_s(), 60.0);
  EXPECT_EQ(opened.effective_config().frame_samples(), 4096u);
  EXPECT_EQ(opened.effective_config().filter().particles(), 1024u);

  const auto estimates = stream.estimates();
  ASSERT_NO_FATAL_FAILURE(ExpectOfflineEstimates(s, estimates));
  for (const v1::Estimate& e : estimates) {
    EXPECT_GT(e.latency().tdoa_s(), 0.0);
    EXPECT_GE(e.latency().total_s(), e.latency().queue_s());
  }
  // Half-close means finished: the session is gone.
  grpc::ClientContext context;
  v1::ListSessionsResponse list;
  ASSERT_TRUE(stub_->ListSessions(&context, {}, &list).ok());
  EXPECT_EQ(list.sessions_size(), 0);
}

// Past the resume history's capacity the outbox hands the estimates it lets go back to the
// runner, which fills them again (EstimatePool): what the client reads must not change.
TEST_F(ServiceTest, EstimatesReusedPastTheResumeHistoryStillEqualOfflineTracking) {
  const Scenario s = MakeScenario("tetra-water", 64.0, 2, kBlock);  // ~340 frames at this scene's rate
  ASSERT_GT(s.offline.size(), Outbox::kHistoryEstimates + 32);
  TestStream stream(stub_.get());
  ASSERT_NO_FATAL_FAILURE(StreamWhole(s, &stream));
  const auto estimates = stream.estimates();
  ASSERT_NO_FATAL_FAILURE(ExpectOfflineEstimates(s, estimates));
  for (const v1::Estimate& e : estimates) EXPECT_EQ(e.pairs_size(), estimates[0].pairs_size());
}

TEST_F(ServiceTest, Pcm16BlocksTrackTheSource) {
  const Scenario s = MakeScenario("tetra-water", 4.0, 3, kBlock);
  TestStream stream(stub_.get());
  ASSERT_TRUE(stream.Send(s.OpenRequest()));
  for (int64_t k = 1; k <= s.BlockCount(kBlock); ++k) ASSERT_TRUE(stream.Send(s.BlockRequest(k, kBlock, true)));
  ASSERT_TRUE(stream.Close().ok());
  const auto estimates = stream.estimates();
  ASSERT_EQ(estimates.size(), s.offline.size());
  // 16-bit quantisation of a signal at ~0.1-1 full scale is far below the sensor noise:
  // the last estimate lands where the float run's does, within 3 x the float run's own
  // position sd, and within 3 of its own sds of the truth (a particle filter amplifies any
  // change in its input into a different resampling history, so the two runs differ by a
  // fraction of their uncertainty or a little more: 0.7 sd with the default motion's
  // persistent levels, turn rates and speed changes, under 0.5 sd with one std; 2.6 sd since
  // acquisition solves with the cross pairs, the float run 0.011 m and the 16-bit one 0.069 m
  // from the truth at a 0.030 m sd).
  const v1::Estimate& last = estimates.back();
  const engine::Estimate& want = s.offline.back();
  ASSERT_TRUE(last.initialised());
  const double d = std::hypot(last.position_m().x() - want.state(0), last.position_m().y() - want.state(1),
                              last.position_m().z() - want.state(2));
  const double sd_m = std::sqrt(want.covariance.topLeftCorner<3, 3>().trace());
  EXPECT_LT(d, 3.0 * sd_m) << "sd " << sd_m;
  const engine::Vec3 truth = s.sim.TruthAt(want.t_s).position_m;
  ASSERT_EQ(last.covariance_size(), 36);
  const double own_sd_m = std::sqrt(last.covariance(0) + last.covariance(7) + last.covariance(14));
  EXPECT_LT(std::hypot(last.position_m().x() - truth.x(), last.position_m().y() - truth.y(),
                       last.position_m().z() - truth.z()),
            3.0 * own_sd_m);
}

TEST_F(ServiceTest, ConcurrentSessionsWithDifferentArraysDoNotInterfere) {
  const Scenario a = MakeScenario("tetra-water", 3.0, 5, kBlock);
  const Scenario b = MakeScenario("turn-multipath", 3.0, 6, kBlock);
  ASSERT_NE(a.config.sensors_m.size(), b.config.sensors_m.size());
  TestStream sa(stub_.get());
  TestStream sb(stub_.get());
  ASSERT_TRUE(sa.Send(a.OpenRequest()));
  ASSERT_TRUE(sb.Send(b.OpenRequest()));
  // Interleave the two streams block by block.
  const int64_t n = std::max(a.BlockCount(kBlock), b.BlockCount(kBlock));
  for (int64_t k = 1; k <= n; ++k) {
    if (k <= a.BlockCount(kBlock)) {
      ASSERT_TRUE(sa.Send(a.BlockRequest(k, kBlock)));
    }
    if (k <= b.BlockCount(kBlock)) {
      ASSERT_TRUE(sb.Send(b.BlockRequest(k, kBlock)));
    }
  }
  ASSERT_TRUE(sa.Close().ok());
  ASSERT_TRUE(sb.Close().ok());
  const auto ea = sa.estimates();
  const auto eb = sb.estimates();
  ASSERT_EQ(ea.size(), a.offline.size());
  ASSERT_EQ(eb.size(), b.offline.size());
  for (size_t i = 0; i < ea.size(); ++i) ExpectSameEstimate(a.offline[i], ea[i]);
  for (size_t i = 0; i < eb.size(); ++i) ExpectSameEstimate(b.offline[i], eb[i]);
  EXPECT_NE(sa.opened().session_id(), sb.opened().session_id());
}

TEST_F(ServiceTest, ListSessionsShowsAnOpenSession) {
  const Scenario s = MakeScenario("tetra-water", 2.0, 1, kBlock);
  TestStream stream(stub_.get());
  ASSERT_TRUE(stream.Send(s.OpenRequest()));
  for (int64_t k = 1; k <= 4; ++k) ASSERT_TRUE(stream.Send(s.BlockRequest(k, kBlock)));
  ASSERT_TRUE(stream.WaitForEstimates(3));
  grpc::ClientContext context;
  v1::ListSessionsResponse list;
  ASSERT_TRUE(stub_->ListSessions(&context, {}, &list).ok());
  ASSERT_EQ(list.sessions_size(), 1);
  const v1::SessionInfo& info = list.sessions(0);
  EXPECT_EQ(info.session_id(), stream.opened().session_id());
  EXPECT_EQ(info.label(), "test");
  EXPECT_TRUE(info.attached());
  EXPECT_EQ(info.channel_count(), 4u);
  EXPECT_EQ(info.last_sequence(), 4u);
  EXPECT_EQ(info.blocks_processed(), 4u);
  ASSERT_TRUE(stream.Close().ok());
}

}  // namespace
}  // namespace localizer::server::testing
