// One session held by the server: its runner (what the kind of session does), its inbox and
// outbox, and the stream attached to it.
//
//   reader (gRPC thread) --Offer--> inbox --worker turn--> runner --> outbox --> stream
//
// The host keeps the lifecycle (open, attach, detach, close, drain), the lock, the worker
// turn and the token check; what a request becomes and what a work item produces is the
// runner's (session_runner.h), ordering and sequence rules the inbox's (inbox.h), replay
// on resume the outbox's (outbox.h).
// * One worker at a time runs a session (the `scheduled` flag), so its items are processed
//   in order; the runner's engine session is touched only by that worker.
// * Backpressure: when the inbox is full Offer says "stop reading" and gRPC flow control
//   holds the client back until the host asks the stream to read again (ReadMore).
//   Processing pauses while max_outbox responses wait to be written.
//
// The stream contract (stream_sink.h). The host decides; the stream acts:
// * The host hands the attached stream its next response (StreamSink::Write) when none is
//   in flight, asks it to read again after a pause (ReadMore) and ends it (End) -- always
//   with the host's lock held. A sink never calls back into the host from those calls.
// * The stream reports what happened to it through the public methods below (Offer,
//   InputDone, WriteDone, EndStream, Detach), which take the host's lock themselves: the
//   stream calls them holding no lock of the host's (its own is never held across them).
// * A stream stays attached until it detaches (its OnDone), even after it was ended, so a
//   write in flight is settled (written, or first again for a resume). A resume on another
//   stream replaces it at once: its write in flight goes first again, it ends ABORTED.
// * Finish: once the client half-closed (InputDone) and every accepted item has produced its
//   responses and they are written, the session is forgotten by the registry (on_finished)
//   and closed, and the stream ends OK -- so nothing can find the session after the client
//   saw OK. A stream that was cancelled ends CANCELLED instead and the session stays; a
//   draining server ends it UNAVAILABLE.
//
// Thread-safety: every public method may be called from any thread and takes the host's
// lock; the lock is never held while calling the runner's Process or Decode*.
// Lock order: host -> a stream's own lock; host -> registry (on_finished).
#pragma once

#include <grpcpp/support/status.h>

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "engine/pipeline/session.h"
#include "localizer/v1/localizer.pb.h"
#include "server/service/inbox.h"
#include "server/service/memory_budget.h"
#include "server/service/outbox.h"
#include "server/service/service_metrics.h"
#include "server/service/session_runner.h"
#include "server/service/stream_sink.h"
#include "server/service/track_history.h"
#include "server/service/worker_pool.h"
#include "server/sync/mutex.h"
#include "wire/block_wire.h"

namespace localizer::server {

struct HostLimits {
  // Requests (blocks, IMU batches, scans, refusals) waiting for the worker before the reader
  // stops reading (--max-queue-blocks).
  int max_queued_requests = 8;
  size_t max_outbox = 256;  // responses waiting to be written before processing pauses
  double ttl_s = 60.0;      // reported in SessionOpened; the registry enforces it
};

class SessionHost final : public std::enable_shared_from_this<SessionHost> {
 public:
  // `on_finished` runs (with the host's lock held) when the session finishes cleanly,
  // before the stream sees OK, with the session's final counters (Info's): the registry
  // forgets the session there (and keeps it for the live view). `charge` is the
  // session's share of the server's memory budget, returned when the host is destroyed
  // (with the runner whose memory it stands for).
  SessionHost(std::string id, std::string token, std::string label, std::unique_ptr<SessionRunner> runner,
              HostLimits limits, WorkerPool* pool, ServiceMetrics* metrics,
              std::function<void(const v1::SessionInfo&)> on_finished, MemoryBudget::Charge charge = {});

  const std::string& id() const { return id_; }
  const std::string& resume_token() const { return token_; }  // a secret: never log it
  const std::string& label() const { return label_; }
  const RunnerInfo& runner_info() const { return runner_->info(); }
  const std::string& backend() const { return runner_->info().backend; }
  // An audio session's config (fixed at creation, so readable from any thread); a detection
  // session's is the default one (no array).
  const engine::AudioSessionConfig& config() const { return runner_->config(); }
  // Recent positions for the live view; locks itself (see track_history.h).
  const TrackHistory& track() const { return track_; }
  bool TokenMatches(const std::string& token) const;  // constant-time comparison

  // --- the stream's side (see the contract above) ---
  // Attaches `sink`, replacing (ending ABORTED) any stream still attached, and writes
  // SessionOpened first, after the replay `resume` asks for (outbox.h). False when the
  // session was closed meanwhile (nothing attached).
  bool Attach(StreamSink* sink, bool resumed, const ResumePoint& resume) EXCLUDES(mutex_);
  // A request with a block, IMU batch or scan from `sink`'s reader: decoded by the runner
  // (outside the lock; `scratch` is the stream's block buffer), then queued. Returns true
  // when the reader may read on; false when the inbox is full (the host calls
  // sink->ReadMore once there is room) or the stream no longer takes input (ended,
  // replaced, draining, session closed: the request is dropped).
  bool Offer(StreamSink* sink, const v1::TrackRequest& request, Clock::time_point received, wire::DecodedBlock* scratch)
      EXCLUDES(mutex_);
  // The client half-closed: finish once everything accepted is answered and written.
  void InputDone(StreamSink* sink) EXCLUDES(mutex_);
  // The write the host handed `sink` completed: written (`ok`), or the stream broke (the
  // response stays for a resume and the stream ends CANCELLED).
  void WriteDone(StreamSink* sink, bool ok) EXCLUDES(mutex_);
  // `sink` ends its stream with `status` (cancelled, a bad request); the session stays.
  void EndStream(StreamSink* sink, const grpc::Status& status) EXCLUDES(mutex_);
  // `sink` is done (gRPC's OnDone): forgotten if still attached. Returns whether the session
  // is still open (detached, resumable).
  bool Detach(StreamSink* sink) EXCLUDES(mutex_);

  // --- lifecycle ---
  // Ends the session: the attached stream (if any) ends with `status`; queued requests are
  // dropped. Idempotent.
  void Close(const grpc::Status& status) EXCLUDES(mutex_);
  // Server shutdown: the attached stream stops reading and ends UNAVAILABLE once idle.
  void Drain() EXCLUDES(mutex_);
  // Nothing queued or running and nothing left to write (or no stream to write to).
  bool Drained() const EXCLUDES(mutex_);
  bool attached() const EXCLUDES(mutex_);
  // kDetached: detached for longer than `ttl_s`. kIdle: attached, but nothing accepted,
  // queued or running for longer than `idle_s` since the later of the attach and the last
  // accepted request (0: never) -- a client that opens and sends nothing holds no slot forever.
  enum class Expiry { kNone, kDetached, kIdle };
  Expiry ExpiryAt(Clock::time_point now, double ttl_s, double idle_s) const EXCLUDES(mutex_);
  // For ListSessions, CloseSession and GET /sessions.
  v1::SessionInfo Info(Clock::time_point now, double ttl_s) const EXCLUDES(mutex_);

  // Worker entry: processes queued items in order, a few per turn, then resubmits itself
  // if more remain (so sessions share the workers fairly).
  void RunTurn() EXCLUDES(mutex_);

 private:
  // Submits a turn unless one is pending or nothing can be processed now.
  void ScheduleLocked() REQUIRES(mutex_);
  // Hands the stream its next response, or finishes the stream when all is done.
  void PumpLocked() REQUIRES(mutex_);
  void EndStreamLocked(const grpc::Status& status) REQUIRES(mutex_);
  void CloseLocked(const grpc::Status& status) REQUIRES(mutex_);
  // Nothing queued, nothing processing: every accepted item has produced its responses.
  bool IdleLocked() const REQUIRES(mutex_) { return inbox_.empty() && !running_; }
  v1::SessionOpened OpenedLocked(bool resumed) const REQUIRES(mutex_);
  v1::SessionInfo InfoLocked(Clock::time_point now, double ttl_s) const REQUIRES(mutex_);

  static constexpr int kItemsPerTurn = 4;  // per worker turn, so that sessions share the workers

  const MemoryBudget::Charge charge_;  // destroyed after runner_ (declared before it)
  const std::string id_;
  const std::string token_;
  const std::string label_;
  const std::unique_ptr<SessionRunner> runner_;  // Process: by the scheduled worker only
  const HostLimits limits_;
  WorkerPool* const pool_;
  ServiceMetrics* const metrics_;
  const std::function<void(const v1::SessionInfo&)> on_finished_;
  const Clock::time_point created_;
  TrackHistory track_;  // appended by the runner; has its own lock
  // RunTurn's responses of the item in hand, by the scheduled worker only (like runner_'s
  // Process); kept so that an item allocates no vector.
  std::vector<ResponsePtr> turn_responses_;

  mutable Mutex mutex_;
  Inbox inbox_ GUARDED_BY(mutex_);
  Outbox outbox_ GUARDED_BY(mutex_);
  bool scheduled_ GUARDED_BY(mutex_) = false;  // a turn is submitted or running
  bool running_ GUARDED_BY(mutex_) = false;    // a worker is processing an item
  bool closed_ GUARDED_BY(mutex_) = false;
  // The attached stream, and what the host knows of it.
  StreamSink* sink_ GUARDED_BY(mutex_) = nullptr;
  bool stream_ended_ GUARDED_BY(mutex_) = false;            // End was called; it stays until it detaches
  bool input_done_ GUARDED_BY(mutex_) = false;              // the client half-closed, or draining
  bool draining_ GUARDED_BY(mutex_) = false;                // the server is shutting down
  bool input_paused_ GUARDED_BY(mutex_) = false;            // Offer said "stop reading"; no ReadMore since
  Clock::time_point stream_changed_at_ GUARDED_BY(mutex_);  // the latest attach or detach
};

}  // namespace localizer::server
