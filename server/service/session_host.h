// One session held by the server: the engine Session plus what the service needs around it.
//
//   reader (gRPC thread) --Offer--> queue --worker--> engine Session --> outbox --> writer
//
// * Queue: accepted blocks (and the in-order rejections of bad ones) wait here for a
//   worker; at most `max_queue_blocks` items, then Offer says "stop reading" and gRPC
//   flow control holds the client back until InputSpaceLocked.
// * One worker at a time runs a session (the `scheduled` flag), so its frames are
//   processed in order; the engine Session is touched only by that worker.
// * Outbox: responses not yet written to a stream. It survives a broken stream; a
//   resume writes it first. History: the last kHistoryEstimates estimates written, for a
//   resume that says which frame it saw last.
// * Sequence rules (checked at Offer, under the lock): a block whose sequence is not
//   greater than the last accepted one is rejected ("duplicate" if equal, "out_of_order"
//   if less) and changes nothing; a jump reports a SequenceGap and the engine skips the
//   missing time (missing blocks x this block's length).
//
// Thread-safety: public methods lock the session's mutex; "Locked" methods require the
// caller to hold it (mutex()).
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "engine/pipeline/scan_session.h"
#include "engine/pipeline/session.h"
#include "localizer/v1/localizer.pb.h"
#include "server/service/service_metrics.h"
#include "server/service/stream_sink.h"
#include "server/service/track_history.h"
#include "server/service/worker_pool.h"
#include "wire/block_wire.h"
#include "wire/imu_wire.h"
#include "wire/scan_wire.h"

namespace localizer::server {

using Clock = std::chrono::steady_clock;
using ResponsePtr = std::shared_ptr<const v1::TrackResponse>;

struct HostLimits {
  int max_queue_blocks = 8;
  size_t max_outbox = 256;  // responses waiting to be written before processing pauses
  double ttl_s = 60.0;      // reported in SessionOpened; the registry enforces it
};

class SessionHost final : public std::enable_shared_from_this<SessionHost> {
 public:
  static constexpr size_t kHistoryEstimates = 256;

  SessionHost(std::string id, std::string token, std::string label, std::unique_ptr<engine::Session> session,
              HostLimits limits, WorkerPool* pool, ServiceMetrics* metrics);
  // A detection session: scans in, track lists out (engine/pipeline/scan_session.h).
  SessionHost(std::string id, std::string token, std::string label, std::unique_ptr<engine::ScanSession> scans,
              HostLimits limits, WorkerPool* pool, ServiceMetrics* metrics);
  ~SessionHost();

  const std::string& id() const { return id_; }
  const std::string& resume_token() const { return token_; }  // a secret: never log it
  const std::string& label() const { return label_; }
  const std::string& backend() const { return backend_; }
  // An audio session's config (fixed at creation, so readable from any thread); a detection
  // session's is the default one (no array).
  const engine::AudioSessionConfig& config() const { return config_; }
  bool detections() const { return scans_ != nullptr; }
  // Recent initialised positions for the live view; locks itself (see track_history.h).
  const TrackHistory& track() const { return track_; }
  bool TokenMatches(const std::string& token) const;  // constant-time comparison
  const wire::BlockLimits& block_limits() const { return block_limits_; }
  std::mutex& mutex() const { return mutex_; }

  // Attaches a stream, replacing (and ending with ABORTED) any stream still attached, and
  // puts SessionOpened first in the outbox. With `last_frame_received`, estimates after
  // that frame still in the history are queued again (before unwritten ones); with
  // `received_none`, every estimate still in the history is (frame 0 included).
  void AttachLocked(StreamSink* sink, bool resumed, std::optional<uint64_t> last_frame_received,
                    bool received_none = false);
  // The stream is gone (its reactor is done). No-op if `sink` is no longer attached.
  void DetachLocked(StreamSink* sink);
  bool attached() const;

  // A decoded block (or the rejection its decoding produced: `rejection` set). Returns
  // true when the reader may read on, false when the queue is full (wait for
  // InputSpaceLocked). `decoded.samples` is taken; a recycled buffer is left in its place.
  bool OfferLocked(wire::DecodedBlock* decoded, const Status& decode_status, const std::string& reason,
                   uint64_t sequence, Clock::time_point received);

  // A decoded IMU batch of a moving-array session (or the rejection its decoding produced),
  // queued in order with the blocks: the engine takes its samples before the blocks sent
  // after it. Same flow control as OfferLocked.
  bool OfferImuLocked(StatusOr<wire::DecodedImu> decoded, uint64_t batch_sequence, Clock::time_point received);
  // A decoded scan of a detection session (or its decoding's rejection); answered in order
  // with a TrackList. Same flow control as OfferLocked.
  bool OfferScanLocked(StatusOr<engine::Scan> decoded, uint64_t scan_sequence, Clock::time_point received);

  // Writer side: the next response to write, or null. MarkWrittenLocked after a write
  // succeeded; RequeueLocked puts a failed write back at the front.
  ResponsePtr NextOutputLocked();
  bool HasOutputLocked() const { return !outbox_.empty(); }
  void MarkWrittenLocked(const ResponsePtr& response);
  void RequeueLocked(ResponsePtr response);
  // Nothing queued, nothing processing: every accepted block has produced its responses.
  bool IdleLocked() const { return queue_.empty() && !running_; }

  // Ends the session: the attached stream (if any) ends with `status`; queued blocks are
  // dropped. Idempotent.
  void Close(const grpc::Status& status);
  void CloseLocked(const grpc::Status& status);
  bool ClosedLocked() const { return closed_; }
  // Server shutdown: the attached stream stops reading and ends once idle (DrainLocked).
  void Drain();
  // Nothing queued or running and nothing left to write (or no stream to write to).
  bool Drained() const;

  // For ListSessions and the expiry sweep.
  v1::SessionInfo Info(Clock::time_point now, double ttl_s) const;
  // Detached for longer than `ttl_s`.
  bool ExpiredLocked(Clock::time_point now, double ttl_s) const;
  v1::SessionOpened OpenedMessageLocked(bool resumed) const;

  // Worker entry: processes queued items in order, a few per turn, then resubmits itself
  // if more remain (so sessions share the workers fairly).
  void RunTurn();

 private:
  struct WorkItem {
    uint64_t sequence = 0;
    std::vector<float> samples;      // channel-major; empty for response-only items
    int64_t samples_per_channel = 0;
    int64_t skip_samples = 0;        // gap before this block
    ResponsePtr response;            // emitted in order before the block (gap/rejection)
    Clock::time_point received;
    std::optional<wire::DecodedImu> imu;  // an IMU batch instead of a block
    uint64_t imu_sequence = 0;
    std::optional<engine::Scan> scan;     // a scan (detection sessions)
    uint64_t scan_sequence = 0;
  };

  void ScheduleLocked();
  void PushOutputLocked(ResponsePtr response);
  // Queues a BlockRejected in order behind the blocks already queued.
  void RejectLocked(uint64_t sequence, const std::string& reason, const Status& status,
                    Clock::time_point received);
  std::vector<ResponsePtr> Process(WorkItem& item, Clock::time_point started);
  std::vector<ResponsePtr> ProcessScan(WorkItem& item);
  // Queues a response-only or scan/IMU item; returns whether the reader may read on.
  bool QueueLocked(WorkItem item);

  const std::string id_;
  const std::string token_;
  const std::string label_;
  const std::unique_ptr<engine::Session> session_;  // audio sessions; used by the scheduled worker only
  const std::unique_ptr<engine::ScanSession> scans_;  // detection sessions; likewise
  const engine::AudioSessionConfig config_;
  const std::string backend_;
  const HostLimits limits_;
  const wire::BlockLimits block_limits_;
  WorkerPool* const pool_;
  ServiceMetrics* const metrics_;
  const Clock::time_point created_;
  std::vector<engine::Estimate> estimates_;  // worker scratch
  TrackHistory track_;                       // appended by the worker; has its own lock

  mutable std::mutex mutex_;
  StreamSink* sink_ = nullptr;                // guarded by mutex_
  Clock::time_point detached_since_;          // guarded by mutex_
  std::deque<WorkItem> queue_;                // guarded by mutex_
  size_t queued_blocks_ = 0;                  // blocks (not responses) in queue_
  std::vector<std::vector<float>> free_buffers_;  // recycled sample buffers
  std::deque<ResponsePtr> outbox_;            // guarded by mutex_
  std::deque<ResponsePtr> history_;           // estimates written, oldest first
  bool scheduled_ = false;                    // a turn is submitted or running
  bool running_ = false;                      // a worker is inside Process
  bool closed_ = false;
  bool input_paused_ = false;                 // Offer returned false and no space since
  std::optional<uint64_t> last_accepted_;     // sequence
  uint64_t blocks_ = 0, frames_ = 0, rejections_ = 0;
  Clock::time_point last_block_;
};

}  // namespace localizer::server
