// Sessions outlive their streams: a resume continues with no estimate lost or repeated;
// wrong tokens, unknown and expired sessions are refused with the documented codes;
// CloseSession and the session limit.
#include <grpcpp/generic/generic_stub.h>

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

// Track over a generic stub: a client that writes raw bytes (here: garbage after a valid
// open), one operation at a time on a completion queue.
class RawTrack {
 public:
  explicit RawTrack(const std::shared_ptr<grpc::Channel>& channel) : stub_(channel) {
    context_.AddMetadata("x-localizer-session-key", "test");
    call_ = stub_.PrepareCall(&context_, "/localizer.v1.Localizer/Track", &cq_);
    call_->StartCall(Tag(1));
    EXPECT_TRUE(Wait(1));
  }
  ~RawTrack() {
    cq_.Shutdown();
    void* tag;
    bool ok;
    while (cq_.Next(&tag, &ok)) {
    }
  }
  bool WriteBytes(const std::string& bytes) {
    grpc::Slice slice(bytes);
    grpc::ByteBuffer buffer(&slice, 1);
    call_->Write(buffer, Tag(2));
    return Wait(2);
  }
  bool Write(const v1::TrackRequest& request) { return WriteBytes(request.SerializeAsString()); }
  bool Read(v1::TrackResponse* response) {
    grpc::ByteBuffer buffer;
    call_->Read(&buffer, Tag(3));
    if (!Wait(3)) return false;
    return grpc::SerializationTraits<v1::TrackResponse>::Deserialize(&buffer, response).ok();
  }
  grpc::Status Finish() {
    v1::TrackResponse ignored;
    while (Read(&ignored)) {
    }
    grpc::Status status;
    call_->Finish(&status, Tag(4));
    Wait(4);
    return status;
  }

 private:
  static void* Tag(intptr_t n) { return reinterpret_cast<void*>(n); }
  bool Wait(intptr_t n) {
    void* tag = nullptr;
    bool ok = false;
    EXPECT_TRUE(cq_.Next(&tag, &ok));
    EXPECT_EQ(tag, Tag(n));
    return ok;
  }

  grpc::GenericStub stub_;
  grpc::ClientContext context_;
  grpc::CompletionQueue cq_;
  std::unique_ptr<grpc::GenericClientAsyncReaderWriter> call_;
};

// A block field (3) announcing 16 bytes and carrying 3: truncated, fails to parse.
const std::string kTruncated(
    "\x1a\x10"
    "abc",
    5);

TEST_F(ServiceTest, UnparseableRequestIsInvalidArgumentAndTheSessionResumes) {
  const Scenario s = MakeScenario("tetra-water", 2.0, 1, kBlock);
  RawTrack raw(channel_);
  ASSERT_TRUE(raw.Write(s.OpenRequest()));
  v1::SessionOpened opened;
  std::vector<v1::Estimate> received;
  v1::TrackResponse response;
  ASSERT_TRUE(raw.Read(&response));
  ASSERT_TRUE(response.has_opened());
  opened = response.opened();
  for (int64_t k = 1; k <= 3; ++k) ASSERT_TRUE(raw.Write(s.BlockRequest(k, kBlock)));
  while (received.size() < 2 && raw.Read(&response)) {
    if (response.has_estimate()) received.push_back(response.estimate());
  }
  ASSERT_EQ(received.size(), 2u);
  raw.WriteBytes(kTruncated);
  const grpc::Status status = raw.Finish();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();
  EXPECT_NE(status.error_message().find("could not be parsed"), std::string::npos) << status.error_message();

  // Not a finish: the session is still there and resumes where the client left off.
  grpc::ClientContext context;
  v1::ListSessionsResponse list;
  ASSERT_TRUE(stub_->ListSessions(&context, {}, &list).ok());
  ASSERT_EQ(list.sessions_size(), 1);
  EXPECT_EQ(list.sessions(0).session_id(), opened.session_id());

  TestStream resumed(stub_.get());
  ASSERT_TRUE(resumed.Send(ResumeRequest(opened, received.back().frame_index())));
  ASSERT_TRUE(resumed.WaitFor([](const auto& r) { return !r.empty(); }));
  EXPECT_TRUE(resumed.opened().resumed());
  for (int64_t k = 4; k <= s.BlockCount(kBlock); ++k) ASSERT_TRUE(resumed.Send(s.BlockRequest(k, kBlock)));
  ASSERT_TRUE(resumed.Close().ok());
  for (const auto& e : resumed.estimates()) received.push_back(e);
  ASSERT_EQ(received.size(), s.offline.size());
  for (size_t i = 0; i < received.size(); ++i) {
    SCOPED_TRACE(i);
    ExpectSameEstimate(s.offline[i], received[i]);
  }
}

TEST_F(ServiceTest, UnparseableFirstRequestIsInvalidArgument) {
  RawTrack raw(channel_);
  raw.WriteBytes(kTruncated);
  const grpc::Status status = raw.Finish();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << status.error_message();
}

// A client whose stream broke before its first estimate says so (received_none) and gets
// every estimate the server holds, frame 0 first; last_frame_received 0 would skip frame 0
// and leaving it unset would skip every estimate already written.
// Locate is registered raw too: bytes that are not a LocateRequest are INVALID_ARGUMENT with
// a message (gRPC's typed handler answered UNIMPLEMENTED with none), and a valid request sent
// the same way still gets its answer.
TEST_F(ServiceTest, UnparseableLocateIsInvalidArgumentWithAMessage) {
  grpc::GenericStub stub(channel_);
  auto call = [&](const std::string& bytes, grpc::ByteBuffer* reply) {
    grpc::CompletionQueue cq;
    grpc::ClientContext context;
    grpc::Slice slice(bytes);
    const grpc::ByteBuffer request(&slice, 1);
    auto reader = stub.PrepareUnaryCall(&context, "/localizer.v1.Localizer/Locate", request, &cq);
    reader->StartCall();
    grpc::Status status;
    reader->Finish(reply, &status, reinterpret_cast<void*>(1));
    void* tag = nullptr;
    bool ok = false;
    EXPECT_TRUE(cq.Next(&tag, &ok));
    cq.Shutdown();
    while (cq.Next(&tag, &ok)) {
    }
    return status;
  };
  grpc::ByteBuffer reply;
  // 14 bytes: the garbage and a trailing NUL.
  const grpc::Status garbage = call(std::string("\xff\xff\xff\xff\x0f garbage\0", 14), &reply);
  EXPECT_EQ(garbage.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(garbage.error_message().find("could not be parsed"), std::string::npos) << garbage.error_message();
  // A well-formed request through the raw path: the same answer as the typed client gets.
  const Scenario s = MakeScenario("tetra-water", 1.0, 2, 4096);
  v1::LocateRequest request;
  *request.mutable_config() = wire::ConfigToProto(s.config, "raw-locate");
  const std::vector<float> samples = s.Block(1, 4096);
  const engine::BlockView view{1, s.sim.channel_count, static_cast<int64_t>(samples.size()) / s.sim.channel_count,
                               samples.data()};
  wire::EncodeBlock(view, false, request.mutable_block());
  const grpc::Status good = call(request.SerializeAsString(), &reply);
  ASSERT_TRUE(good.ok()) << good.error_message();
  v1::LocateResponse response;
  ASSERT_TRUE(grpc::SerializationTraits<v1::LocateResponse>::Deserialize(&reply, &response).ok());
  EXPECT_EQ(response.pairs_size(), s.sim.channel_count - 1);
}

TEST_F(ServiceTest, ResumeWithReceivedNoneReplaysFromFrameZero) {
  const Scenario s = MakeScenario("tetra-water", 2.0, 1, kBlock);
  v1::SessionOpened opened;
  size_t written = 0;
  {
    TestStream first(stub_.get());
    ASSERT_TRUE(first.Send(s.OpenRequest()));
    for (int64_t k = 1; k <= 4; ++k) ASSERT_TRUE(first.Send(s.BlockRequest(k, kBlock)));
    ASSERT_TRUE(first.WaitForEstimates(3));  // written by the server (the client "lost" them)
    written = first.estimates().size();
    opened = first.opened();
    first.Cancel();
  }
  v1::TrackRequest resume = ResumeRequest(opened, std::nullopt);
  resume.mutable_resume()->set_received_none(true);
  TestStream second(stub_.get());
  ASSERT_TRUE(second.Send(resume));
  for (int64_t k = 5; k <= s.BlockCount(kBlock); ++k) ASSERT_TRUE(second.Send(s.BlockRequest(k, kBlock)));
  ASSERT_TRUE(second.Close().ok());
  const auto estimates = second.estimates();
  ASSERT_GE(written, 3u);
  ASSERT_EQ(estimates.size(), s.offline.size());
  for (size_t i = 0; i < estimates.size(); ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(estimates[i].frame_index(), i);
    ExpectSameEstimate(s.offline[i], estimates[i]);
  }

  // Both at once is refused.
  v1::TrackRequest both = ResumeRequest(opened, 0);
  both.mutable_resume()->set_received_none(true);
  TestStream third(stub_.get());
  ASSERT_TRUE(third.Send(both));
  EXPECT_EQ(third.Close().error_code(), grpc::StatusCode::INVALID_ARGUMENT);
}

TEST_F(ServiceTest, OversizedSessionRefsAreInvalidArgumentWithoutEcho) {
  const std::string huge = "evil\r\nlevel=error " + std::string(100000, 'A');
  v1::SessionOpened forged;
  forged.set_session_id(huge);
  forged.set_resume_token("t");
  TestStream stream(stub_.get());
  ASSERT_TRUE(stream.Send(ResumeRequest(forged, std::nullopt)));
  grpc::Status status = stream.Close();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("session_id"), std::string::npos) << status.error_message();
  EXPECT_NE(status.error_message().find("64"), std::string::npos) << status.error_message();
  EXPECT_LT(status.error_message().size(), 200u);
  EXPECT_EQ(status.error_message().find('\n'), std::string::npos);

  v1::CloseSessionRequest close;
  close.set_session_id("0123456789abcdef");
  close.set_resume_token(huge);
  v1::CloseSessionResponse response;
  grpc::ClientContext context;
  status = stub_->CloseSession(&context, close, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("resume_token"), std::string::npos) << status.error_message();
  EXPECT_LT(status.error_message().size(), 200u);
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

class ShortIdleTest : public ServiceTest {
 protected:
  void SetUp() override {
    ServerOptions options;
    options.session_idle_timeout_s = 1.0;
    options.max_sessions = 1;
    StartServer(options);
  }
};

TEST_F(ShortIdleTest, AnAttachedSessionThatSendsNothingIsClosedAndFreesItsSlot) {
  // The review's lock-out: attached sessions that never send a block never expired, and
  // max_sessions of them refused every new client. A session that streams stays; one that
  // goes quiet is ended DEADLINE_EXCEEDED and its slot is free again.
  const Scenario s = MakeScenario("tetra-water", 3.0, 1, kBlock);  // 8 blocks
  TestStream quiet(stub_.get());
  ASSERT_TRUE(quiet.Send(s.OpenRequest()));
  ASSERT_TRUE(quiet.WaitFor([](const auto& r) { return !r.empty(); }));
  const grpc::Status ended = quiet.Finish();
  EXPECT_EQ(ended.error_code(), grpc::StatusCode::DEADLINE_EXCEEDED) << ended.error_message();
  EXPECT_NE(ended.error_message().find("--session-idle-timeout"), std::string::npos) << ended.error_message();
  TestStream busy(stub_.get());
  ASSERT_TRUE(busy.Send(s.OpenRequest()));  // the slot is free again
  for (int64_t k = 1; k <= 8; ++k) {
    std::this_thread::sleep_for(std::chrono::milliseconds(250));  // 2 s in all: twice the idle limit
    ASSERT_TRUE(busy.Send(s.BlockRequest(k, kBlock)));
  }
  ASSERT_TRUE(busy.Close().ok());
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
