// A session's outputs on their way to a stream: the responses waiting to be written, the one
// being written, and the history of estimates written, kept for a resume.
//
//   worker --Push--> waiting --TakeNext--> in flight --Written--> history (estimates only)
//                       ^                      |
//                       +------- Failed -------+   (a broken write; also a stream replaced)
//
// One response is in flight at a time. It survives a broken stream: Failed (or Reattach, when
// a resume replaces the stream it was written to) puts it first again; a SessionOpened is
// dropped instead (every attach writes a fresh one).
// Resume (Reattach): with `received_none` every estimate still in the history is queued again,
// oldest first, before what waits; with `last_frame_received` the estimates the client has
// (frame <= it) leave the waiting queue and the history's later ones are queued again before
// it; with neither only what was never written is sent. The new stream's SessionOpened goes
// first of all.
// An estimate the history lets go goes to the session's EstimatePool (when one is given and
// nothing else holds it), for the runner to fill again.
// Not thread-safe: the session host guards its outbox with its own lock.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <vector>

#include "localizer/v1/localizer.pb.h"
#include "server/sync/mutex.h"

namespace localizer::server {

using ResponsePtr = std::shared_ptr<const v1::TrackResponse>;

// What a resuming client says it has (ResumeSession.last_frame_received / received_none).
struct ResumePoint {
  std::optional<uint64_t> last_frame_received;
  bool received_none = false;
};

// Estimate responses kept for reuse. The outbox hands back each estimate its history lets go
// (Put: only when nothing else holds it), the session's runner fills one again (TakeEstimate)
// instead of building a new one. A TrackResponse keeps its Estimate, and the Estimate its
// sub-messages, repeated fields and strings, through Clear; so once a session's history is
// full (256 estimates, ~12 s of real-time blocks) an estimate allocates nothing: no malloc per
// sub-message on the worker, no free of them on the gRPC thread that wrote it (which handed
// the chunks back to the worker's malloc arena, or kept them in its own cache, so that the
// worker's heap grew again whenever the sessions' share of the two workers shifted).
// Thread-safe: Put runs with the session host's lock held, TakeEstimate on the worker without
// it; its own lock is held for a push or a pop only (lock order: host -> pool).
class EstimatePool final {
 public:
  static constexpr size_t kCapacity = 8;  // two estimates a block come and go: a few suffice

  // Keeps `response` if it is an estimate nothing else holds and there is room; else drops it.
  void Put(ResponsePtr response) EXCLUDES(mutex_);
  // A response whose estimate is set and empty (as a new one's): a recycled one, or new.
  std::shared_ptr<v1::TrackResponse> TakeEstimate() EXCLUDES(mutex_);
  size_t size() const EXCLUDES(mutex_);

 private:
  mutable Mutex mutex_;
  std::vector<std::shared_ptr<v1::TrackResponse>> spare_ GUARDED_BY(mutex_);
};

class Outbox final {
 public:
  static constexpr size_t kHistoryEstimates = 256;

  // `pool` (may be null) receives the estimates the history lets go; it must outlive the outbox.
  explicit Outbox(size_t history_capacity = kHistoryEstimates, EstimatePool* pool = nullptr);
  Outbox(const Outbox&) = delete;
  Outbox& operator=(const Outbox&) = delete;

  // A response produced by the worker, written after everything already waiting. Estimates
  // and track lists count as frames.
  void Push(ResponsePtr response);
  // The next response to write, now in flight; null when nothing waits or one is in flight.
  ResponsePtr TakeNext();
  // The response in flight reached the stream: an estimate joins the history.
  void Written();
  // The response in flight did not: it goes first again (a SessionOpened is dropped).
  void Failed();
  // A stream (re)attaches: the response in flight on the previous one, if any, goes first
  // again (as Failed), then the replay `resume` asks for, then `opened` before everything.
  void Reattach(ResponsePtr opened, const ResumePoint& resume);

  size_t waiting() const { return waiting_.size(); }  // the response in flight excluded
  bool writing() const { return in_flight_ != nullptr; }
  size_t history_size() const { return history_.size(); }
  uint64_t frames() const { return frames_; }  // estimates and track lists pushed

 private:
  const size_t history_capacity_;
  EstimatePool* const pool_;
  std::deque<ResponsePtr> waiting_;
  ResponsePtr in_flight_;
  std::deque<ResponsePtr> history_;  // estimates written, oldest first
  uint64_t frames_ = 0;
};

}  // namespace localizer::server
