#include "clients/loadgen/load_session.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include "clients/grpc/connection.h"
#include "wire/status_wire.h"
#include "wire/tsan_annotations.h"

namespace localizer::loadgen {

namespace {

// RpcMethod keeps the pointer: the name must outlive every call.
const std::string& TrackMethod() {
  static const std::string name = "/localizer.v1.Localizer/Track";
  return name;
}

// How often the pacer looks at a session that waits for gRPC (closing, or at max rate).
constexpr int64_t kClosingPollNs = 100'000'000;

int64_t ToNs(double seconds) { return static_cast<int64_t>(std::llround(seconds * 1e9)); }

}  // namespace

int64_t NowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

LoadSession::LoadSession(int index, int64_t start_ns, TrackStub* stub, const SessionShared& shared)
    : index_(index),
      start_ns_(start_ns),
      period_ns_(ToNs(shared.options->block_period_s())),
      end_ns_(start_ns + ToNs(shared.options->duration_s)),
      drain_ns_(ToNs(shared.options->drain_timeout_s)),
      realtime_(shared.options->pacing == client::Pacing::kRealtime),
      stub_(stub),
      shared_(shared) {
  const std::string open = shared.workload->OpenRequest(index);
  grpc::Slice slice(open);
  open_buffer_ = grpc::ByteBuffer(&slice, 1);
  client::SetSessionKey(&context_, "loadgen-" + std::to_string(index));
}

void LoadSession::Open() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    phase_ = Phase::kOpening;
    write_in_flight_ = true;  // the open request
    next_due_ns_ = start_ns_;
  }
  shared_.stats->started.fetch_add(1, std::memory_order_relaxed);
  stub_->PrepareBidiStreamingCall(&context_, TrackMethod(), grpc::StubOptions(), this);
  AddHold();  // released once no more writes will be started (ReleaseIfQuiet)
  StartWrite(&open_buffer_);
  StartRead(&read_buffer_);
  // Before StartCall, which starts what the two calls above only noted (tsan_annotations.h):
  // one address per path, the write path's (open, then blocks), the read path's and OnDone's.
  wire::TsanRelease(&write_buffer_);
  wire::TsanRelease(&read_buffer_);
  wire::TsanRelease(this);
  StartCall();
}

void LoadSession::Skip() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    phase_ = Phase::kDone;
  }
  shared_.stats->finished.fetch_add(1, std::memory_order_release);  // the runner may free us now
}

int64_t LoadSession::CancelPast(int64_t deadline_ns, int64_t now_ns, int64_t poll_ns, const char* error,
                                Action* action) {
  if (now_ns < deadline_ns) return std::min(now_ns + poll_ns, deadline_ns);
  cancelled_ = true;
  action->cancel = true;
  shared_.stats->CountError(error);
  return -1;
}

LoadSession::Action LoadSession::Decide(int64_t now_ns) {
  Action action;
  if (phase_ != Phase::kStreaming || write_in_flight_) return action;
  const bool time_up = realtime_ ? next_due_ns_ >= end_ns_ : now_ns >= end_ns_;
  if (time_up || shared_.stop->load(std::memory_order_relaxed)) {
    phase_ = Phase::kClosing;
    closing_ns_ = now_ns;
    action.writes_done = true;
    ReleaseIfQuiet(&action);
    return action;
  }
  if (realtime_) {
    if (next_due_ns_ > now_ns) return action;
    action.behind_ns = now_ns - next_due_ns_;
    next_due_ns_ += period_ns_;
  }
  const uint64_t sequence = next_sequence_++;
  const std::string& body = shared_.workload->body(static_cast<int>((sequence - 1) % shared_.workload->block_count()));
  char prefix[Workload::kMaxPrefixBytes];
  const int prefix_bytes = Workload::BlockPrefix(sequence, body.size(), prefix);
  grpc::Slice slices[2] = {grpc::Slice(prefix, prefix_bytes),
                           grpc::Slice(body.data(), body.size(), grpc::Slice::STATIC_SLICE)};
  write_buffer_ = grpc::ByteBuffer(slices, 2);
  ring_sequence_[sequence % kSendRing] = sequence;
  ring_send_ns_[sequence % kSendRing] = now_ns;
  write_in_flight_ = true;
  action.write = true;
  return action;
}

void LoadSession::ReleaseIfQuiet(Action* action) {
  const bool quiet = (phase_ == Phase::kClosing || phase_ == Phase::kEnded) && !write_in_flight_;
  if (quiet && !hold_released_) {
    hold_released_ = true;
    action->release_hold = true;
  }
}

void LoadSession::Perform(const Action& action, int64_t now_ns) {
  LoadStats& stats = *shared_.stats;
  if (action.write) {
    stats.NoteSend(now_ns);
    if (realtime_) {
      stats.NoteBehind(action.behind_ns);
      if (action.behind_ns > period_ns_) stats.late_blocks.fetch_add(1, std::memory_order_relaxed);
    }
    wire::TsanRelease(&write_buffer_);
    StartWrite(&write_buffer_);
  }
  // What this thread did comes before OnDone, which any of these may bring on.
  if (action.writes_done || action.release_hold || action.cancel) wire::TsanRelease(this);
  if (action.writes_done) StartWritesDone();
  if (action.release_hold) RemoveHold();
  if (action.cancel) context_.TryCancel();
}

int64_t LoadSession::Tick(int64_t now_ns) {
  Action action;
  int64_t next_ns = -1;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    switch (phase_) {
      case Phase::kOpening:
        next_ns = CancelPast(start_ns_ + drain_ns_, now_ns, period_ns_, "OPEN_TIMEOUT", &action);
        break;
      case Phase::kStreaming:
        action = Decide(now_ns);
        if (phase_ == Phase::kClosing) {
          next_ns = now_ns + kClosingPollNs;
        } else if (realtime_) {
          // With a write in flight, its completion sends what is due; look again later.
          next_ns = write_in_flight_ ? std::max(next_due_ns_, now_ns + period_ns_ / 2) : next_due_ns_;
        } else {
          // Max rate: writes chain themselves; look at the end time, then every 100 ms.
          next_ns = now_ns < end_ns_ ? std::min(now_ns + kClosingPollNs, end_ns_) : now_ns + kClosingPollNs;
        }
        break;
      case Phase::kClosing:
        // Looked at again soon: the pacer is done with the session once it has ended.
        next_ns = CancelPast(closing_ns_ + drain_ns_, now_ns, kClosingPollNs, "DRAIN_TIMEOUT", &action);
        break;
      case Phase::kWaiting:  // Open comes first; nothing to do
      case Phase::kEnded:    // the stream is over; OnDone follows
      case Phase::kDone:
        break;
    }
  }
  Perform(action, now_ns);
  return next_ns;
}

void LoadSession::OnWriteDone(bool ok) {
  wire::TsanAcquire(&write_buffer_);
  const int64_t now_ns = NowNs();
  Action action;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    write_in_flight_ = false;
    if (!ok && (phase_ == Phase::kOpening || phase_ == Phase::kStreaming)) phase_ = Phase::kEnded;
    action = Decide(now_ns);  // the next block when it is due (max: always)
    ReleaseIfQuiet(&action);
  }
  Perform(action, now_ns);
}

void LoadSession::OnReadDone(bool ok) {
  wire::TsanAcquire(&read_buffer_);
  const int64_t now_ns = NowNs();
  if (!ok) {  // the stream is over; OnDone brings its status
    Action action;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (phase_ == Phase::kOpening || phase_ == Phase::kStreaming) phase_ = Phase::kEnded;
      ReleaseIfQuiet(&action);
    }
    Perform(action, now_ns);
    return;
  }
  const grpc::Status parsed = grpc::SerializationTraits<v1::TrackResponse>::Deserialize(&read_buffer_, &response_);
  read_buffer_.Clear();
  if (parsed.ok()) {
    Received(response_, now_ns);
  } else {
    shared_.stats->CountError("PROTOCOL");  // bytes that are no TrackResponse
  }
  wire::TsanRelease(&read_buffer_);
  StartRead(&read_buffer_);
}

void LoadSession::Received(const v1::TrackResponse& response, int64_t now_ns) {
  LoadStats& stats = *shared_.stats;
  bool opening;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    opening = !first_response_seen_;
    first_response_seen_ = true;
  }
  if (opening) {
    Action action;
    if (response.kind_case() == v1::TrackResponse::kOpened) {
      stats.opened.fetch_add(1, std::memory_order_relaxed);
      stats.live.fetch_add(1, std::memory_order_relaxed);
      stats.CountBackend(response.opened().backend());
      std::lock_guard<std::mutex> lock(mutex_);
      opened_ = true;
      if (phase_ == Phase::kOpening) phase_ = Phase::kStreaming;
      action = Decide(now_ns);  // the first block (realtime: its time has come already)
    } else {
      stats.CountError("PROTOCOL");  // something other than `opened` came first
      std::lock_guard<std::mutex> lock(mutex_);
      cancelled_ = true;
      action.cancel = true;
    }
    Perform(action, now_ns);
    return;
  }
  switch (response.kind_case()) {
    case v1::TrackResponse::kEstimate: {
      const uint64_t sequence = response.estimate().sequence();
      int64_t sent_ns = -1;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (ring_sequence_[sequence % kSendRing] == sequence && sequence != 0) {
          sent_ns = ring_send_ns_[sequence % kSendRing];
        }
      }
      stats.estimates.fetch_add(1, std::memory_order_relaxed);
      // Whether the engine did the work of a tracked source: the same for both generators.
      if (response.estimate().initialised()) stats.initialised.fetch_add(1, std::memory_order_relaxed);
      if (response.estimate().source_present()) stats.present.fetch_add(1, std::memory_order_relaxed);
      stats.NoteEstimate(now_ns);
      if (sent_ns >= 0) {
        stats.latency.Add(1e-9 * static_cast<double>(now_ns - sent_ns));
      } else {
        stats.unmatched.fetch_add(1, std::memory_order_relaxed);
      }
      break;
    }
    case v1::TrackResponse::kRejected: {
      const v1::BlockRejected& rejected = response.rejected();
      stats.CountRejection(!rejected.reason().empty() ? rejected.reason() : rejected.code());
      break;
    }
    case v1::TrackResponse::kGap:
      stats.gaps.fetch_add(1, std::memory_order_relaxed);
      break;
    default:
      stats.CountError("PROTOCOL");
      break;
  }
}

void LoadSession::OnDone(const grpc::Status& status) {
  wire::TsanAcquire(this);
  wire::TsanAcquire(&read_buffer_);
  wire::TsanAcquire(&write_buffer_);
  bool cancelled, opened;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    phase_ = Phase::kDone;
    cancelled = cancelled_;
    opened = opened_;
  }
  LoadStats& stats = *shared_.stats;
  const grpc::Status end = client::FromProxyReset(status);
  if (!end.ok() && !cancelled) {
    if (end.error_code() == grpc::StatusCode::RESOURCE_EXHAUSTED) {
      stats.CountRejection(std::string("session_") + wire::GrpcCodeName(end.error_code()));
    } else {
      stats.CountError(wire::GrpcCodeName(end.error_code()));
    }
  } else if (end.ok() && !opened && !shared_.stop->load(std::memory_order_relaxed)) {
    stats.CountError("NO_OPENED");  // the stream ended OK without `opened`
  }
  if (opened) stats.live.fetch_sub(1, std::memory_order_relaxed);
  // Last, and a release: the runner's acquire load of `finished` then orders everything this
  // session did before its destruction.
  stats.finished.fetch_add(1, std::memory_order_release);
}

}  // namespace localizer::loadgen
