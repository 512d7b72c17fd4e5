// Sessions outlive their streams: a resume continues with no estimate lost or repeated;
// wrong tokens, unknown and expired sessions are refused with the documented codes;
// CloseSession and the session limit.
#include <set>

#include "tests/server/service_fixture.h"

namespace localizer::server::testing {
namespace {

constexpr int64_t kBlock = 2048;

v1::TrackRequest ResumeRequest(const v1::SessionOpened& opened, std::optional<uint64_t> last_frame) {
  v1::TrackRequest request;
  request.mutable_resume()->set_session_id(opened.session_id());
  request.mutable_resume()->set_resume_token(opened.resume_token());
  if (last_frame) request.mutable_resume()->set_last_frame_received(*last_frame);
  return request;
}

TEST_F(ServiceTest, ResumeAfterDisconnectLosesAndRepeatsNothing) {
  const Scenario s = MakeScenario("tetra-water", 4.0, 1, kBlock);
  const int64_t blocks = s.BlockCount(kBlock);
  std::vector<v1::Estimate> received;
  v1::SessionOpened opened;
  {
    TestStream first(stub_.get());
    ASSERT_TRUE(first.Send(s.OpenRequest()));
    for (int64_t k = 1; k <= 10; ++k) ASSERT_TRUE(first.Send(s.BlockRequest(k, kBlock)));
    ASSERT_TRUE(first.WaitForEstimates(4));
    const grpc::Status cancelled = first.Cancel();
    EXPECT_EQ(cancelled.error_code(), grpc::StatusCode::CANCELLED) << cancelled.error_message();
    received = first.estimates();
    opened = first.opened();
  }
  ASSERT_FALSE(received.empty());
  const uint64_t last_frame = received.back().frame_index();

  TestStream second(stub_.get());
  ASSERT_TRUE(second.Send(ResumeRequest(opened, last_frame)));
  ASSERT_TRUE(second.WaitFor([](const auto& r) { return !r.empty(); }));
  const v1::SessionOpened resumed = second.opened();
  EXPECT_TRUE(resumed.resumed());
  EXPECT_EQ(resumed.session_id(), opened.session_id());
  // At least the blocks behind the estimates received were accepted; blocks still in
  // flight when the stream broke may not have been.
  EXPECT_GE(resumed.last_sequence(), 5u);
  EXPECT_LE(resumed.last_sequence(), 10u);
  for (int64_t k = resumed.last_sequence() + 1; k <= blocks; ++k) ASSERT_TRUE(second.Send(s.BlockRequest(k, kBlock)));
  ASSERT_TRUE(second.Close().ok());
  for (const auto& e : second.estimates()) received.push_back(e);

  ASSERT_EQ(received.size(), s.offline.size());
  for (size_t i = 0; i < received.size(); ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(received[i].frame_index(), i);
    ExpectSameEstimate(s.offline[i], received[i]);
  }
}

TEST_F(ServiceTest, ResumeRefusals) {
  const Scenario s = MakeScenario("tetra-water", 1.0, 1, kBlock);
  TestStream first(stub_.get());
  ASSERT_TRUE(first.Send(s.OpenRequest()));
  ASSERT_TRUE(first.WaitFor([](const auto& r) { return !r.empty(); }));
  const v1::SessionOpened opened = first.opened();

  v1::SessionOpened forged = opened;
  forged.set_resume_token(std::string(32, '0'));
  TestStream wrong(stub_.get());
  ASSERT_TRUE(wrong.Send(ResumeRequest(forged, std::nullopt)));
  EXPECT_EQ(wrong.Close().error_code(), grpc::StatusCode::PERMISSION_DENIED);

  forged = opened;
  forged.set_session_id("0123456789abcdef");
  TestStream unknown(stub_.get());
  ASSERT_TRUE(unknown.Send(ResumeRequest(forged, std::nullopt)));
  EXPECT_EQ(unknown.Close().error_code(), grpc::StatusCode::NOT_FOUND);

  // The refusals did not disturb the session.
  for (int64_t k = 1; k <= 3; ++k) ASSERT_TRUE(first.Send(s.BlockRequest(k, kBlock)));
  ASSERT_TRUE(first.Close().ok());
  EXPECT_EQ(first.estimates().size(), 2u);
}

class ShortTtlTest : public ServiceTest {
 protected:
  void SetUp() override {
    ServerOptions options;
    options.session_ttl_s = 0.3;
    options.max_sessions = 2;
    StartServer(options);
  }
};

TEST_F(ShortTtlTest, DetachedSessionExpires) {
  const Scenario s = MakeScenario("tetra-water", 1.0, 1, kBlock);
  v1::SessionOpened opened;
  {
    TestStream first(stub_.get());
    ASSERT_TRUE(first.Send(s.OpenRequest()));
    ASSERT_TRUE(first.Send(s.BlockRequest(1, kBlock)));
    ASSERT_TRUE(first.WaitFor([](const auto& r) { return !r.empty(); }));
    opened = first.opened();
    first.Cancel();
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(1000));
  TestStream late(stub_.get());
  ASSERT_TRUE(late.Send(ResumeRequest(opened, std::nullopt)));
  const grpc::Status status = late.Close();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::NOT_FOUND) << status.error_message();
}

TEST_F(ShortTtlTest, SessionLimitIsResourceExhausted) {
  const Scenario s = MakeScenario("tetra-water", 1.0, 1, kBlock);
  TestStream a(stub_.get()), b(stub_.get());
  ASSERT_TRUE(a.Send(s.OpenRequest()));
  ASSERT_TRUE(b.Send(s.OpenRequest()));
  ASSERT_TRUE(a.WaitFor([](const auto& r) { return !r.empty(); }));
  ASSERT_TRUE(b.WaitFor([](const auto& r) { return !r.empty(); }));
  TestStream c(stub_.get());
  ASSERT_TRUE(c.Send(s.OpenRequest()));
  EXPECT_EQ(c.Close().error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  ASSERT_TRUE(a.Close().ok());
  ASSERT_TRUE(b.Close().ok());
}

TEST_F(ServiceTest, CloseSessionEndsTheStreamAndNeedsTheToken) {
  const Scenario s = MakeScenario("tetra-water", 1.0, 1, kBlock);
  TestStream stream(stub_.get());
  ASSERT_TRUE(stream.Send(s.OpenRequest()));
  for (int64_t k = 1; k <= 3; ++k) ASSERT_TRUE(stream.Send(s.BlockRequest(k, kBlock)));
  ASSERT_TRUE(stream.WaitForEstimates(2));
  const v1::SessionOpened opened = stream.opened();

  v1::CloseSessionRequest request;
  request.set_session_id(opened.session_id());
  request.set_resume_token("nope");
  v1::CloseSessionResponse response;
  {
    grpc::ClientContext context;
    EXPECT_EQ(stub_->CloseSession(&context, request, &response).error_code(), grpc::StatusCode::PERMISSION_DENIED);
  }
  request.set_resume_token(opened.resume_token());
  {
    grpc::ClientContext context;
    ASSERT_TRUE(stub_->CloseSession(&context, request, &response).ok());
    EXPECT_EQ(response.frames_processed(), 2u);
  }
  EXPECT_EQ(stream.Finish().error_code(), grpc::StatusCode::CANCELLED);
  grpc::ClientContext context;
  v1::ListSessionsResponse list;
  ASSERT_TRUE(stub_->ListSessions(&context, {}, &list).ok());
  EXPECT_EQ(list.sessions_size(), 0);
  grpc::ClientContext again;
  EXPECT_EQ(stub_->CloseSession(&again, request, &response).error_code(), grpc::StatusCode::NOT_FOUND);
}

}  // namespace
}  // namespace localizer::server::testing
