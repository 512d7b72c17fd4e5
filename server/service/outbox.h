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
// Not thread-safe: the session host guards its outbox with its own lock.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>

#include "localizer/v1/localizer.pb.h"

namespace localizer::server {

using ResponsePtr = std::shared_ptr<const v1::TrackResponse>;

// What a resuming client says it has (ResumeSession.last_frame_received / received_none).
struct ResumePoint {
  std::optional<uint64_t> last_frame_received;
  bool received_none = false;
};

class Outbox final {
 public:
  static constexpr size_t kHistoryEstimates = 256;

  explicit Outbox(size_t history_capacity = kHistoryEstimates);
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
  std::deque<ResponsePtr> waiting_;
  ResponsePtr in_flight_;
  std::deque<ResponsePtr> history_;  // estimates written, oldest first
  uint64_t frames_ = 0;
};

}  // namespace localizer::server
