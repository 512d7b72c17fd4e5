// The session inbox on its own: order, the sequence rules (duplicate, out of order, gaps and
// the skip they cause), flow control counting every kind of item, the counts SessionInfo
// reports, the shared queue-depth gauge, and sample buffers going back to the reader.
#include "server/service/inbox.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace localizer::server {
namespace {

const Clock::time_point kT0 = Clock::now();

WorkItem Block(uint64_t sequence, int64_t samples_per_channel = 100, int channels = 4) {
  BlockWork work;
  work.sequence = sequence;
  work.samples_per_channel = samples_per_channel;
  work.samples.assign(static_cast<size_t>(samples_per_channel * channels), 0.5f);
  // Received 1 ms apart (capped: a test's far sequence numbers must not overflow the clock).
  return {std::move(work), kT0 + std::chrono::milliseconds(std::min<uint64_t>(sequence, 1000000))};
}

WorkItem Refused(RequestKind request, uint64_t sequence, const std::string& reason) {
  return {Rejection{request, sequence, reason, InvalidArgument("bad")}, kT0};
}

TEST(Inbox, ItemsLeaveInOrderOfArrival) {
  Inbox inbox(8, nullptr, kT0);
  std::vector<float> spare;
  inbox.Offer(Block(1), &spare);
  inbox.Offer(Refused(RequestKind::kBlock, 7, "non_finite"), &spare);
  inbox.Offer({ImuWork{3, {}}, kT0}, &spare);
  inbox.Offer(Block(2), &spare);
  ASSERT_EQ(inbox.size(), 4u);
  auto a = inbox.Take();
  ASSERT_TRUE(a && std::holds_alternative<BlockWork>(a->work));
  EXPECT_EQ(std::get<BlockWork>(a->work).sequence, 1u);
  auto b = inbox.Take();
  ASSERT_TRUE(b && std::holds_alternative<Rejection>(b->work));
  EXPECT_EQ(std::get<Rejection>(b->work).sequence, 7u);
  auto c = inbox.Take();
  ASSERT_TRUE(c && std::holds_alternative<ImuWork>(c->work));
  auto d = inbox.Take();
  ASSERT_TRUE(d && std::holds_alternative<BlockWork>(d->work));
  EXPECT_EQ(std::get<BlockWork>(d->work).sequence, 2u);
  EXPECT_FALSE(inbox.Take());
  EXPECT_TRUE(inbox.empty());
}

TEST(Inbox, DuplicateAndOutOfOrderBlocksBecomeRejectionsAndChangeNothing) {
  Inbox inbox(8, nullptr, kT0);
  std::vector<float> spare;
  inbox.Offer(Block(5), &spare);
  ASSERT_EQ(inbox.last_sequence(), 5u);

  WorkItem again = Block(5);
  const size_t samples = std::get<BlockWork>(again.work).samples.size();
  Inbox::Offered offered = inbox.Offer(std::move(again), &spare);
  ASSERT_NE(offered.rejected, nullptr);
  EXPECT_EQ(offered.rejected->reason, "duplicate");
  EXPECT_EQ(offered.rejected->request, RequestKind::kBlock);
  EXPECT_EQ(offered.rejected->sequence, 5u);
  EXPECT_EQ(offered.rejected->status.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(offered.rejected->status.message().find("repeats the last accepted block's"), std::string::npos);
  EXPECT_EQ(spare.size(), samples) << "a refused block's samples go back to the reader";

  offered = inbox.Offer(Block(3), &spare);
  ASSERT_NE(offered.rejected, nullptr);
  EXPECT_EQ(offered.rejected->reason, "out_of_order");
  EXPECT_NE(offered.rejected->status.message().find("is below the last accepted block's 5"), std::string::npos);

  EXPECT_EQ(inbox.last_sequence(), 5u);
  EXPECT_EQ(inbox.queued_blocks(), 1u);  // the refusals wait in order, but are not blocks
  EXPECT_EQ(inbox.size(), 3u);
  EXPECT_EQ(inbox.blocks_rejected(), 2u);
  EXPECT_FALSE(offered.gap);
}

TEST(Inbox, AJumpRecordsTheGapAndTheSamplesToSkip) {
  Inbox inbox(8, nullptr, kT0);
  std::vector<float> spare;
  EXPECT_FALSE(inbox.Offer(Block(1, 100), &spare).gap);  // the first block: no gap, whatever its number
  EXPECT_FALSE(inbox.Offer(Block(2, 100), &spare).gap);
  EXPECT_TRUE(inbox.Offer(Block(6, 250), &spare).gap);
  (void)inbox.Take();
  (void)inbox.Take();
  auto item = inbox.Take();
  ASSERT_TRUE(item);
  const BlockWork& block = std::get<BlockWork>(item->work);
  ASSERT_TRUE(block.gap);
  EXPECT_EQ(block.gap->previous_sequence, 2u);
  EXPECT_EQ(block.gap->missing_blocks, 3u);
  EXPECT_EQ(block.gap->skipped_samples, 3u * 250u);  // missing blocks x this block's length
  EXPECT_EQ(block.skip_samples, 750);
}

TEST(Inbox, HugeGapsAreCapped) {
  Inbox inbox(8, nullptr, kT0);
  std::vector<float> spare;
  inbox.Offer(Block(1, 10), &spare);
  const uint64_t far = uint64_t{1} << 50;
  EXPECT_TRUE(inbox.Offer(Block(far, 10), &spare).gap);
  (void)inbox.Take();
  auto item = inbox.Take();
  const BlockWork& block = std::get<BlockWork>(item->work);
  EXPECT_EQ(block.gap->missing_blocks, far - 2);
  EXPECT_EQ(block.gap->skipped_samples, (uint64_t{1} << 20) * 10u);  // at most 2^20 blocks
  EXPECT_EQ(block.skip_samples, int64_t{10} << 20);
}

TEST(Inbox, EveryKindOfItemTakesASlot) {
  Inbox inbox(3, nullptr, kT0);
  std::vector<float> spare;
  EXPECT_TRUE(inbox.Offer(Refused(RequestKind::kImu, 1, "imu"), &spare).room);
  EXPECT_TRUE(inbox.Offer({ScanWork{1, {}}, kT0}, &spare).room);
  EXPECT_FALSE(inbox.Offer(Block(1), &spare).room) << "three items fill a capacity of three";
  EXPECT_FALSE(inbox.has_room());
  (void)inbox.Take();
  EXPECT_TRUE(inbox.has_room());
}

TEST(Inbox, CountsWhatSessionInfoReports) {
  metrics::Gauge depth;
  Inbox inbox(8, &depth, kT0);
  std::vector<float> spare;
  EXPECT_EQ(inbox.last_accepted_at(), kT0);
  EXPECT_FALSE(inbox.last_sequence());
  inbox.Offer(Block(1), &spare);
  inbox.Offer(Block(2), &spare);
  inbox.Offer(Refused(RequestKind::kBlock, 9, "channel_count"), &spare);
  inbox.Offer(Refused(RequestKind::kScan, 4, "not_detections"), &spare);  // not a block: not counted
  inbox.Offer(Refused(RequestKind::kImu, 4, "not_moving"), &spare);
  EXPECT_EQ(inbox.queued_blocks(), 2u);
  EXPECT_EQ(depth.value(), 2.0);
  EXPECT_EQ(inbox.blocks_rejected(), 1u);
  EXPECT_EQ(inbox.last_accepted_at(), kT0 + std::chrono::milliseconds(2));  // when block 2 arrived

  auto first = inbox.Take();
  EXPECT_EQ(inbox.queued_blocks(), 1u);
  EXPECT_EQ(depth.value(), 1.0);
  EXPECT_EQ(inbox.blocks_processed(), 0u);
  inbox.Done(*first);
  EXPECT_EQ(inbox.blocks_processed(), 1u);
  (void)inbox.Take();  // block 2
  auto refusal = inbox.Take();
  inbox.Done(*refusal);
  EXPECT_EQ(inbox.blocks_processed(), 1u) << "a refusal is not a processed block";

  // A scan is a detection session's activity; an IMU batch is not.
  const Clock::time_point later = kT0 + std::chrono::seconds(5);
  inbox.Offer({ImuWork{1, {}}, later}, &spare);
  EXPECT_EQ(inbox.last_accepted_at(), kT0 + std::chrono::milliseconds(2));
  inbox.Offer({ScanWork{1, {}}, later}, &spare);
  EXPECT_EQ(inbox.last_accepted_at(), later);
}

TEST(Inbox, ClearAndDestructionGiveBackTheGauge) {
  metrics::Gauge depth;
  {
    Inbox inbox(8, &depth, kT0);
    std::vector<float> spare;
    inbox.Offer(Block(1), &spare);
    inbox.Offer(Block(2), &spare);
    inbox.Offer(Block(3), &spare);
    EXPECT_EQ(depth.value(), 3.0);
    inbox.Clear();
    EXPECT_EQ(depth.value(), 0.0);
    EXPECT_TRUE(inbox.empty());
    EXPECT_EQ(inbox.last_sequence(), 3u) << "the sequence rules outlive a clear";
    inbox.Offer(Block(4), &spare);
    EXPECT_EQ(depth.value(), 1.0);
  }
  EXPECT_EQ(depth.value(), 0.0);
}

TEST(Inbox, ProcessedBuffersGoBackToTheReader) {
  Inbox inbox(8, nullptr, kT0);
  std::vector<float> spare;
  inbox.Offer(Block(1, 100), &spare);
  EXPECT_TRUE(spare.empty()) << "no buffer to recycle yet";
  auto item = inbox.Take();
  const float* data = std::get<BlockWork>(item->work).samples.data();
  inbox.Done(*item);
  inbox.Offer(Block(2, 100), &spare);
  EXPECT_EQ(spare.data(), data) << "the processed block's buffer, kept with its size";
  EXPECT_EQ(spare.size(), 400u);
}

TEST(Inbox, RequestKindNamesAreTheWireNames) {
  EXPECT_STREQ(RequestKindName(RequestKind::kBlock), "block");
  EXPECT_STREQ(RequestKindName(RequestKind::kImu), "imu");
  EXPECT_STREQ(RequestKindName(RequestKind::kScan), "scan");
}

}  // namespace
}  // namespace localizer::server
