#include "server/service/inbox.h"

#include <algorithm>
#include <utility>

namespace localizer::server {
namespace {

constexpr size_t kFreeBuffers = 4;

}  // namespace

const char* RequestKindName(RequestKind kind) {
  switch (kind) {
    case RequestKind::kBlock:
      return "block";
    case RequestKind::kImu:
      return "imu";
    case RequestKind::kScan:
      return "scan";
  }
  return "block";
}

Inbox::Inbox(size_t capacity, metrics::Gauge* depth, Clock::time_point created)
    : capacity_(capacity), depth_(depth), last_accepted_at_(created) {}

Inbox::~Inbox() { AddQueuedBlocks(-static_cast<int64_t>(queued_blocks_)); }

void Inbox::AddQueuedBlocks(int64_t n) {
  queued_blocks_ = static_cast<uint64_t>(static_cast<int64_t>(queued_blocks_) + n);
  if (depth_ != nullptr && n != 0) depth_->Add(static_cast<double>(n));
}

std::optional<Rejection> Inbox::CheckSequence(BlockWork* block) const {
  if (!last_sequence_) return std::nullopt;
  const uint64_t last = *last_sequence_;
  if (block->sequence <= last) {
    const bool duplicate = block->sequence == last;
    const std::string message = "sequence " + std::to_string(block->sequence) +
                                (duplicate ? " repeats the last accepted block's"
                                           : " is below the last accepted block's " + std::to_string(last)) +
                                "; the block was ignored";
    return Rejection{RequestKind::kBlock, block->sequence, duplicate ? "duplicate" : "out_of_order",
                     InvalidArgument(message)};
  }
  if (block->sequence > last + 1) {
    SequenceGap gap;
    gap.previous_sequence = last;
    gap.missing_blocks = block->sequence - last - 1;
    gap.skipped_samples =
        std::min<uint64_t>(gap.missing_blocks, uint64_t{1} << 20) * static_cast<uint64_t>(block->samples_per_channel);
    block->skip_samples = static_cast<int64_t>(std::min<uint64_t>(gap.skipped_samples, uint64_t{1} << 40));
    block->gap = gap;
  }
  return std::nullopt;
}

Inbox::Offered Inbox::Offer(WorkItem item, std::vector<float>* spare) {
  Offered offered;
  if (auto* block = std::get_if<BlockWork>(&item.work)) {
    if (std::optional<Rejection> refused = CheckSequence(block)) {
      *spare = std::move(block->samples);  // the reader keeps its buffer
      item.work = std::move(*refused);
    } else {
      offered.gap = block->gap.has_value();
      last_sequence_ = block->sequence;
      last_accepted_at_ = item.received;
      AddQueuedBlocks(1);
      if (!free_buffers_.empty()) {
        *spare = std::move(free_buffers_.back());
        free_buffers_.pop_back();
      } else {
        spare->clear();
      }
    }
  } else if (std::holds_alternative<ScanWork>(item.work)) {
    last_accepted_at_ = item.received;  // a detection session's activity is its scans
  }
  if (const auto* rejected = std::get_if<Rejection>(&item.work); rejected && rejected->request == RequestKind::kBlock) {
    ++blocks_rejected_;
  }
  items_.push_back(std::move(item));
  offered.rejected = std::get_if<Rejection>(&items_.back().work);
  offered.room = has_room();
  return offered;
}

std::optional<WorkItem> Inbox::Take() {
  if (items_.empty()) return std::nullopt;
  std::optional<WorkItem> item(std::move(items_.front()));
  items_.pop_front();
  if (std::holds_alternative<BlockWork>(item->work)) AddQueuedBlocks(-1);  // room for the next block
  return item;
}

void Inbox::Done(WorkItem& item) {
  auto* block = std::get_if<BlockWork>(&item.work);
  if (block == nullptr) return;
  ++blocks_processed_;
  // Kept with its size: a block of the same length reuses it without zero-filling.
  if (free_buffers_.size() < kFreeBuffers) free_buffers_.push_back(std::move(block->samples));
}

void Inbox::Clear() {
  AddQueuedBlocks(-static_cast<int64_t>(queued_blocks_));
  items_.clear();
}

}  // namespace localizer::server
