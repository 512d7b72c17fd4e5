// One Track session of a load run, on gRPC's callback API: a ClientBidiReactor whose
// reactions run on gRPC's threads, so a few threads drive hundreds of sessions.
//
// Lifecycle (the proto's Track contract):
//   Open       (pacing thread, at the session's start time) writes the prepared
//              TrackRequest{open} and starts reading. Blocks go out only after `opened`.
//   sending    block k (sequence k, body (k - 1) % block_count) is handed to gRPC
//                realtime: at start + (k - 1) x block period, on an absolute schedule. One
//                  write is in flight at a time (gRPC's rule): a block whose time comes
//                  while the previous write is still in flight goes out as soon as it
//                  completes. Nothing is queued, so memory stays bounded; a block handed
//                  over more than one block period after its time counts as late, and the
//                  most any block was behind is kept.
//                max: the next block as soon as the previous write completes.
//              Sending stops at start + duration (realtime: the blocks due before it), or
//              at once when the run is stopped (Ctrl-C).
//   half-close WritesDone: the server answers every accepted block and ends the stream OK.
//              A stream not ended --drain-timeout after it (or not opened within that of
//              its start) is cancelled and counted as DRAIN_TIMEOUT (OPEN_TIMEOUT).
//   OnDone     the final status: errors by status code (CANCELLED of our own cancel is
//              not one), a session refused with RESOURCE_EXHAUSTED counts as rejected;
//              stats.finished goes up last (a release; the runner polls it with acquire),
//              and nothing of the session is touched after that.
//
// Latency of an estimate: received - the moment the block it names (Estimate.sequence, the
// block that completed its frame) was handed to StartWrite, on the steady clock. Send times
// are kept in a ring of kSendRing blocks; an estimate for a block that fell out of it (over a
// minute behind) counts as unmatched instead.
//
// Threads: Open and Tick from the session's pacing thread; reactions from gRPC's. State is
// guarded by one mutex per session; gRPC is never called with it held (a reaction may run
// inline). A hold keeps OnDone back until the session will start no more operations.
#pragma once

#include <grpcpp/client_context.h>
#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/support/byte_buffer.h>
#include <grpcpp/support/client_callback.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <mutex>

#include "clients/loadgen/load_options.h"
#include "clients/loadgen/load_stats.h"
#include "clients/loadgen/workload.h"
#include "localizer/v1/localizer.grpc.pb.h"

namespace localizer::loadgen {

// Track's requests go out as ready bytes; its responses come in as bytes too and are parsed
// in OnReadDone, after the read path's TSan acquire (wire/tsan_annotations.h): a protobuf
// response type would be parsed by gRPC's inline code before any reaction of ours runs.
using TrackStub = grpc::TemplatedGenericStub<grpc::ByteBuffer, grpc::ByteBuffer>;

// Nanoseconds on the steady clock.
int64_t NowNs();

// What every session of a run shares; everything outlives the sessions.
struct SessionShared {
  const LoadOptions* options = nullptr;
  const Workload* workload = nullptr;
  LoadStats* stats = nullptr;
  const std::atomic<bool>* stop = nullptr;  // Ctrl-C: half-close now
};

class LoadSession final : public grpc::ClientBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer> {
 public:
  static constexpr int kSendRing = 1024;

  LoadSession(int index, int64_t start_ns, TrackStub* stub, const SessionShared& shared);
  LoadSession(const LoadSession&) = delete;
  LoadSession& operator=(const LoadSession&) = delete;

  int index() const { return index_; }
  int64_t start_ns() const { return start_ns_; }

  // Starts the stream. Call once, at start_ns().
  void Open();
  // Never started (the run was stopped first): counted as finished.
  void Skip();
  // Sends what is due, half-closes when time is up, cancels a stream past its deadline.
  // Returns when to call again (steady-clock ns), or -1 when the pacer is done with it.
  int64_t Tick(int64_t now_ns);

  void OnWriteDone(bool ok) override;
  void OnReadDone(bool ok) override;
  void OnWritesDoneDone(bool /*ok*/) override {}
  void OnDone(const grpc::Status& status) override;

 private:
  enum class Phase { kWaiting, kOpening, kStreaming, kClosing, kEnded, kDone };
  // What to do once the mutex is released.
  struct Action {
    bool write = false;
    bool writes_done = false;
    bool release_hold = false;
    bool cancel = false;
    int64_t behind_ns = 0;
  };

  // Under mutex_: the next write or the half-close, if one is due at `now_ns`.
  Action Decide(int64_t now_ns);
  // Under mutex_: past `deadline_ns`, cancels the call (counting `error`) and returns -1;
  // before it, the next look: now + poll_ns, at most the deadline.
  int64_t CancelPast(int64_t deadline_ns, int64_t now_ns, int64_t poll_ns, const char* error, Action* action);
  // Under mutex_: release the hold once no more operations will be started.
  void ReleaseIfQuiet(Action* action);
  void Perform(const Action& action, int64_t now_ns);
  void Received(const v1::TrackResponse& response, int64_t now_ns);

  const int index_;
  const int64_t start_ns_;
  const int64_t period_ns_;  // one block of audio
  const int64_t end_ns_;     // start + duration
  const int64_t drain_ns_;
  const bool realtime_;
  TrackStub* const stub_;
  const SessionShared shared_;

  grpc::ClientContext context_;
  grpc::ByteBuffer open_buffer_;
  grpc::ByteBuffer write_buffer_;  // the block in flight (its body is the workload's)
  grpc::ByteBuffer read_buffer_;   // the read in flight
  v1::TrackResponse response_;     // the last response read, parsed from read_buffer_

  std::mutex mutex_;
  Phase phase_ = Phase::kWaiting;                    // guarded by mutex_
  bool write_in_flight_ = false;                     // guarded by mutex_
  bool hold_released_ = false;                       // guarded by mutex_
  bool cancelled_ = false;                           // guarded by mutex_: by us (deadline, protocol)
  bool first_response_seen_ = false;                 // guarded by mutex_
  bool opened_ = false;                              // guarded by mutex_: the server answered `opened`
  uint64_t next_sequence_ = 1;                       // guarded by mutex_
  int64_t next_due_ns_ = 0;                          // guarded by mutex_ (realtime)
  int64_t closing_ns_ = 0;                           // guarded by mutex_: when WritesDone was started
  std::array<uint64_t, kSendRing> ring_sequence_{};  // guarded by mutex_
  std::array<int64_t, kSendRing> ring_send_ns_{};    // guarded by mutex_
};

}  // namespace localizer::loadgen
