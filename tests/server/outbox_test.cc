// The session outbox on its own: one response in flight, written estimates kept as the
// history (and only estimates, at most the capacity), a broken write first again (a
// SessionOpened dropped instead), and the replay a resume asks for; the estimates the
// history lets go are reused (EstimatePool) only when nothing else holds them, and a reused
// one, filled again, serializes byte for byte as a new one.
#include "server/service/outbox.h"

#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "engine/core/estimate.h"
#include "wire/estimate_wire.h"

namespace localizer::server {
namespace {

ResponsePtr Estimate(uint64_t frame) {
  auto r = std::make_shared<v1::TrackResponse>();
  r->mutable_estimate()->set_frame_index(frame);
  return r;
}
ResponsePtr Tracks(uint64_t scan) {
  auto r = std::make_shared<v1::TrackResponse>();
  r->mutable_tracks()->set_scan_index(scan);
  return r;
}
ResponsePtr Gap() {
  auto r = std::make_shared<v1::TrackResponse>();
  r->mutable_gap()->set_missing_blocks(1);
  return r;
}
ResponsePtr Opened(const std::string& id) {
  auto r = std::make_shared<v1::TrackResponse>();
  r->mutable_opened()->set_session_id(id);
  return r;
}

// Writes everything waiting (each written), returns it.
std::vector<ResponsePtr> WriteAll(Outbox* outbox) {
  std::vector<ResponsePtr> out;
  while (ResponsePtr r = outbox->TakeNext()) {
    out.push_back(r);
    outbox->Written();
  }
  return out;
}

std::vector<uint64_t> Frames(const std::vector<ResponsePtr>& responses) {
  std::vector<uint64_t> frames;
  for (const ResponsePtr& r : responses) {
    if (r->has_estimate()) frames.push_back(r->estimate().frame_index());
  }
  return frames;
}

TEST(Outbox, OneResponseInFlightAtATime) {
  Outbox outbox;
  outbox.Push(Estimate(0));
  outbox.Push(Estimate(1));
  ResponsePtr first = outbox.TakeNext();
  ASSERT_TRUE(first);
  EXPECT_TRUE(outbox.writing());
  EXPECT_EQ(outbox.waiting(), 1u);
  EXPECT_FALSE(outbox.TakeNext()) << "the next waits for the first to complete";
  outbox.Written();
  EXPECT_FALSE(outbox.writing());
  ResponsePtr second = outbox.TakeNext();
  ASSERT_TRUE(second);
  EXPECT_EQ(second->estimate().frame_index(), 1u);
}

TEST(Outbox, FramesCountEstimatesAndTrackLists) {
  Outbox outbox;
  outbox.Push(Gap());
  outbox.Push(Estimate(0));
  outbox.Push(Tracks(0));
  outbox.Push(Opened("s"));
  EXPECT_EQ(outbox.frames(), 2u);
}

TEST(Outbox, OnlyWrittenEstimatesJoinTheHistoryUpToItsCapacity) {
  Outbox outbox(3);
  outbox.Push(Opened("s"));
  outbox.Push(Gap());
  for (uint64_t f = 0; f < 5; ++f) outbox.Push(Estimate(f));
  outbox.Push(Tracks(9));
  WriteAll(&outbox);
  EXPECT_EQ(outbox.history_size(), 3u);
  // Replaying everything held shows which: the last three estimates.
  outbox.Reattach(Opened("s"), ResumePoint{std::nullopt, /*received_none=*/true});
  EXPECT_EQ(Frames(WriteAll(&outbox)), (std::vector<uint64_t>{2, 3, 4}));
}

TEST(Outbox, AFailedWriteGoesFirstAgainButASessionOpenedIsDropped) {
  Outbox outbox;
  outbox.Push(Estimate(0));
  outbox.Push(Estimate(1));
  ASSERT_TRUE(outbox.TakeNext());
  outbox.Failed();
  EXPECT_FALSE(outbox.writing());
  EXPECT_EQ(outbox.waiting(), 2u);
  EXPECT_EQ(Frames(WriteAll(&outbox)), (std::vector<uint64_t>{0, 1}));

  outbox.Push(Opened("s"));
  outbox.Push(Estimate(2));
  ASSERT_TRUE(outbox.TakeNext()->has_opened());
  outbox.Failed();
  EXPECT_EQ(outbox.waiting(), 1u) << "every attach writes a fresh SessionOpened";
  EXPECT_EQ(outbox.history_size(), 2u) << "failed writes do not count as written";
}

TEST(Outbox, ResumeWithNeitherSendsOnlyWhatWasNeverWritten) {
  Outbox outbox;
  for (uint64_t f = 0; f < 3; ++f) outbox.Push(Estimate(f));
  ASSERT_TRUE(outbox.TakeNext());
  outbox.Written();  // frame 0 written
  outbox.Reattach(Opened("s"), ResumePoint{});
  std::vector<ResponsePtr> sent = WriteAll(&outbox);
  ASSERT_FALSE(sent.empty());
  EXPECT_TRUE(sent.front()->has_opened());
  EXPECT_EQ(Frames(sent), (std::vector<uint64_t>{1, 2}));
}

TEST(Outbox, ResumeAfterAFrameDropsWhatTheClientHasAndReplaysTheRest) {
  Outbox outbox;
  for (uint64_t f = 0; f < 6; ++f) outbox.Push(Estimate(f));
  for (int i = 0; i < 4; ++i) {  // frames 0..3 written; the client saw up to 1
    ASSERT_TRUE(outbox.TakeNext());
    outbox.Written();
  }
  outbox.Reattach(Opened("s"), ResumePoint{1, false});
  std::vector<ResponsePtr> sent = WriteAll(&outbox);
  EXPECT_TRUE(sent.front()->has_opened());
  EXPECT_EQ(Frames(sent), (std::vector<uint64_t>{2, 3, 4, 5}));

  // The client already has waiting estimates (it saw them on a stream that broke later):
  // they are dropped, not repeated.
  outbox.Push(Estimate(6));
  outbox.Push(Estimate(7));
  outbox.Reattach(Opened("s"), ResumePoint{6, false});
  EXPECT_EQ(Frames(WriteAll(&outbox)), (std::vector<uint64_t>{7}));
}

TEST(Outbox, ResumeWithNothingReceivedReplaysTheWholeHistoryFrameZeroFirst) {
  Outbox outbox;
  for (uint64_t f = 0; f < 4; ++f) outbox.Push(Estimate(f));
  for (int i = 0; i < 2; ++i) {
    ASSERT_TRUE(outbox.TakeNext());
    outbox.Written();
  }
  outbox.Reattach(Opened("s"), ResumePoint{std::nullopt, true});
  std::vector<ResponsePtr> sent = WriteAll(&outbox);
  EXPECT_TRUE(sent.front()->has_opened());
  EXPECT_EQ(Frames(sent), (std::vector<uint64_t>{0, 1, 2, 3}));
}

TEST(Outbox, TheWriteInFlightOnAReplacedStreamGoesFirstAgain) {
  Outbox outbox;
  outbox.Push(Estimate(0));
  outbox.Push(Estimate(1));
  ASSERT_TRUE(outbox.TakeNext());  // frame 0 in flight when a resume replaces the stream
  outbox.Reattach(Opened("s2"), ResumePoint{});
  EXPECT_FALSE(outbox.writing());
  std::vector<ResponsePtr> sent = WriteAll(&outbox);
  EXPECT_EQ(sent.front()->opened().session_id(), "s2");
  EXPECT_EQ(Frames(sent), (std::vector<uint64_t>{0, 1}));

  // ... unless the client says it has it.
  outbox.Push(Estimate(2));
  outbox.Push(Estimate(3));
  ASSERT_TRUE(outbox.TakeNext());
  outbox.Reattach(Opened("s3"), ResumePoint{2, false});
  EXPECT_EQ(Frames(WriteAll(&outbox)), (std::vector<uint64_t>{3}));
}

// Writes everything waiting, keeping nothing (as the session host does).
void WriteAllDropping(Outbox* outbox) {
  while (outbox->TakeNext()) outbox->Written();
}

TEST(EstimatePool, EstimatesTheHistoryLetsGoComeBackEmpty) {
  EstimatePool pool;
  Outbox outbox(2, &pool);
  for (uint64_t f = 0; f < 5; ++f) {
    auto r = std::make_shared<v1::TrackResponse>();
    r->mutable_estimate()->set_frame_index(f);
    r->mutable_estimate()->set_backend("cpu");
    r->mutable_estimate()->mutable_covariance()->Resize(36, 1.0);
    r->mutable_estimate()->add_pairs()->set_delay_s(1e-3);
    outbox.Push(std::move(r));
  }
  outbox.Push(Gap());  // not an estimate: never kept
  WriteAllDropping(&outbox);
  EXPECT_EQ(outbox.history_size(), 2u);
  EXPECT_EQ(pool.size(), 3u);  // frames 0, 1, 2 left the history
  std::shared_ptr<v1::TrackResponse> reused = pool.TakeEstimate();
  EXPECT_EQ(pool.size(), 2u);
  ASSERT_TRUE(reused->has_estimate());
  EXPECT_EQ(reused->estimate().ByteSizeLong(), 0u);  // nothing of frame 0, 1 or 2 left
  EXPECT_EQ(reused->estimate().covariance_size(), 0);
  EXPECT_EQ(reused->estimate().pairs_size(), 0);
  EXPECT_EQ(reused->estimate().backend(), "");
  // An empty pool builds a new one, in the same shape.
  EstimatePool empty;
  EXPECT_EQ(empty.TakeEstimate()->SerializeAsString(), reused->SerializeAsString());
}

TEST(EstimatePool, AnEstimateHeldElsewhereIsNotReused) {
  EstimatePool pool;
  Outbox outbox(1, &pool);
  for (uint64_t f = 0; f < 3; ++f) outbox.Push(Estimate(f));
  const std::vector<ResponsePtr> written = WriteAll(&outbox);  // holds every response
  EXPECT_EQ(pool.size(), 0u);
  EXPECT_EQ(Frames(written), (std::vector<uint64_t>{0, 1, 2}));
  // A replay holds the history's estimates twice: none goes to the pool while queued.
  outbox.Reattach(Opened("s"), ResumePoint{std::nullopt, true});
  outbox.Push(Estimate(3));
  std::vector<uint64_t> replayed;
  while (ResponsePtr r = outbox.TakeNext()) {
    if (r->has_estimate()) replayed.push_back(r->estimate().frame_index());
    outbox.Written();
  }
  EXPECT_EQ(replayed, (std::vector<uint64_t>{2, 3}));
  EXPECT_EQ(pool.size(), 0u);  // frame 2 left the history twice, held by `written` both times
  for (size_t k = 0; k < written.size(); ++k) EXPECT_EQ(written[k]->estimate().frame_index(), k);
}

engine::Estimate EngineEstimate(uint64_t frame, size_t pairs, bool with_extras) {
  engine::Estimate e;
  e.frame_index = frame;
  e.sequence = frame / 2;
  e.t_s = 0.05 * static_cast<double>(frame);
  e.initialised = true;
  e.state.setConstant(0.25 * static_cast<double>(frame + 1));
  e.covariance.setIdentity();
  e.covariance *= 0.01;
  e.ess = 3000.0;
  e.pairs_used = static_cast<int>(pairs);
  for (size_t k = 0; k < pairs; ++k) {
    e.delay_s.push_back(1e-4 * static_cast<double>(k + 1));
    e.quality.push_back(0.5);
  }
  e.source_present = true;
  e.presence_statistic = 7.0;
  e.presence_threshold = 5.0;
  if (with_extras) {
    e.model_probabilities = {{"cv", 0.7}, {"ct", 0.3}};
    engine::SourceEstimate source;
    source.source_id = 1;
    source.azimuth_rad = 0.5;
    e.sources.push_back(source);
    e.ambiguous = true;
    e.modes = 2;
  }
  return e;
}

TEST(EstimatePool, AReusedEstimateFilledAgainSerializesAsANewOne) {
  // Filled first with more of everything (pairs, model probabilities, sources), then with less:
  // nothing of the first may show in the second.
  EstimatePool pool;
  Outbox outbox(0, &pool);
  auto first = std::make_shared<v1::TrackResponse>();
  wire::EstimateToProto(EngineEstimate(7, 6, true), 0, "cpu", first->mutable_estimate());
  outbox.Push(std::move(first));
  WriteAllDropping(&outbox);
  ASSERT_EQ(pool.size(), 1u);
  const engine::Estimate next = EngineEstimate(8, 3, false);
  std::shared_ptr<v1::TrackResponse> reused = pool.TakeEstimate();
  wire::EstimateToProto(next, 0, "cpu", reused->mutable_estimate());
  v1::TrackResponse fresh;
  wire::EstimateToProto(next, 0, "cpu", fresh.mutable_estimate());
  EXPECT_EQ(reused->SerializeAsString(), fresh.SerializeAsString());
  EXPECT_EQ(reused->estimate().pairs_size(), 3);
}

}  // namespace
}  // namespace localizer::server
