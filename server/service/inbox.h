// A session's inbox: what its reader accepted, waiting for the session's worker, in order.
//
//   reader (gRPC thread) --Offer--> [ WorkItem, WorkItem, ... ] --Take--> worker --Done
//
// A work item is one of (std::variant):
//   Rejection  a request refused at the edge (a bad block, an IMU batch to a fixed array, a
//              scan to an audio session, ...): nothing to process; its BlockRejected is
//              written in order with the outputs of the items around it.
//   BlockWork  an audio session's samples (channel-major), with the SequenceGap before it.
//   ImuWork    a moving array's IMU samples, processed before the blocks sent after them.
//   ScanWork   a detection session's scan.
// Which requests a session takes is its runner's decision (session_runner.h); the inbox
// only orders, counts and applies the sequence rules.
//
// Sequence rules (sample blocks, at Offer): a block whose sequence is not above the last
// accepted one becomes a Rejection ("duplicate" if equal, "out_of_order" if below) and
// changes nothing; a jump (sequence > last + 1) records a SequenceGap, and the engine skips
// the missing time before the block: missing blocks (at most 2^20) x this block's length.
//
// Flow control: `capacity` items may wait (rejections, IMU batches and scans included, so a
// client sending only bad requests is held back as well); Offer says whether there is room
// for another. Counts: blocks waiting (SessionInfo.queued_blocks and the shared gauge
// localizer_queue_depth_blocks), blocks processed, blocks rejected, the last accepted
// sequence, and when the last block or scan was accepted (SessionInfo.idle_s).
// A processed block's sample buffer goes back to the reader (at most 4 are kept), so a
// stream of equal blocks decodes without allocating.
//
// Not thread-safe: the session host guards its inbox with its own lock.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "engine/core/detection.h"
#include "engine/core/status.h"
#include "server/metrics/metric_types.h"
#include "wire/imu_wire.h"

namespace localizer::server {

using Clock = std::chrono::steady_clock;

// What a rejected request was (BlockRejected.request).
enum class RequestKind { kBlock, kImu, kScan };
const char* RequestKindName(RequestKind kind);  // "block" | "imu" | "scan"

struct Rejection {
  RequestKind request = RequestKind::kBlock;
  uint64_t sequence = 0;  // the block's, the IMU batch's or the scan's
  std::string reason;     // BlockRejected.reason, also the rejections metric's label
  Status status;          // BlockRejected.code and .message
};

struct SequenceGap {
  uint64_t previous_sequence = 0;  // the last block accepted before the jump
  uint64_t missing_blocks = 0;
  uint64_t skipped_samples = 0;  // per channel: min(missing_blocks, 2^20) x this block's length
};

struct BlockWork {
  uint64_t sequence = 0;
  std::vector<float> samples;  // channel-major
  int64_t samples_per_channel = 0;
  std::optional<SequenceGap> gap;  // set by the inbox: the jump before this block
  int64_t skip_samples = 0;        // set by the inbox: what the engine skips first (<= 2^40)
};

struct ImuWork {
  uint64_t sequence = 0;  // the batch's
  wire::DecodedImu batch;
};

struct ScanWork {
  uint64_t sequence = 0;
  engine::Scan scan;
};

struct WorkItem {
  std::variant<Rejection, BlockWork, ImuWork, ScanWork> work;
  Clock::time_point received;  // when the reader had the request
};

class Inbox final {
 public:
  // `depth` (may be null) follows the blocks waiting in every session's inbox.
  Inbox(size_t capacity, metrics::Gauge* depth, Clock::time_point created);
  ~Inbox();  // the blocks still waiting leave `depth`
  Inbox(const Inbox&) = delete;
  Inbox& operator=(const Inbox&) = delete;

  struct Offered {
    bool room = true;  // fewer than `capacity` items wait: the reader may read on
    bool gap = false;  // a block accepted after a jump in sequence numbers
    // The refusal queued, when the item was one or became one (a duplicate); valid until
    // the inbox changes.
    const Rejection* rejected = nullptr;
  };
  // Queues `item` behind the others, after the sequence rules. `spare` is the reader's
  // sample buffer: when a block is accepted it receives a recycled buffer (or is cleared);
  // when a block is refused it gets the block's samples back.
  Offered Offer(WorkItem item, std::vector<float>* spare);

  // The oldest item, or none. A block leaves the waiting count here.
  std::optional<WorkItem> Take();
  // `item` (from Take) was processed: counts it and keeps its sample buffer for reuse.
  void Done(WorkItem& item);
  // The session closed: everything waiting is dropped.
  void Clear();

  bool empty() const { return items_.empty(); }
  size_t size() const { return items_.size(); }
  bool has_room() const { return items_.size() < capacity_; }
  uint64_t queued_blocks() const { return queued_blocks_; }
  uint64_t blocks_processed() const { return blocks_processed_; }
  uint64_t blocks_rejected() const { return blocks_rejected_; }
  std::optional<uint64_t> last_sequence() const { return last_sequence_; }
  // When the last block (or scan) was accepted; the inbox's creation before the first.
  Clock::time_point last_accepted_at() const { return last_accepted_at_; }

 private:
  // The sequence rules: a Rejection for a duplicate or out-of-order block, else the gap.
  std::optional<Rejection> CheckSequence(BlockWork* block) const;
  void AddQueuedBlocks(int64_t n);

  const size_t capacity_;
  metrics::Gauge* const depth_;
  std::deque<WorkItem> items_;
  std::vector<std::vector<float>> free_buffers_;
  uint64_t queued_blocks_ = 0;
  uint64_t blocks_processed_ = 0;
  uint64_t blocks_rejected_ = 0;  // refused blocks (SessionInfo.rejections); IMU and scan refusals are not
  std::optional<uint64_t> last_sequence_;
  Clock::time_point last_accepted_at_;
};

}  // namespace localizer::server
