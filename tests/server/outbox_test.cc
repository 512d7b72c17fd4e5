// The session outbox on its own: one response in flight, written estimates kept as the
// history (and only estimates, at most the capacity), a broken write first again (a
// SessionOpened dropped instead), and the replay a resume asks for.
#include "server/service/outbox.h"

#include <gtest/gtest.h>

#include <memory>
#include <vector>

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

}  // namespace
}  // namespace localizer::server
