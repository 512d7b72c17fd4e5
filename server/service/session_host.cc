#include "server/service/session_host.h"

#include <algorithm>

#include "server/service/log.h"
#include "server/service/runner_util.h"
#include "server/service/secure_random.h"
#include "wire/config_wire.h"

namespace localizer::server {

SessionHost::SessionHost(std::string id, std::string token, std::string label, std::unique_ptr<SessionRunner> runner,
                         HostLimits limits, WorkerPool* pool, ServiceMetrics* metrics,
                         std::function<void(const v1::SessionInfo&)> on_finished, MemoryBudget::Charge charge)
    : charge_(std::move(charge)),
      id_(std::move(id)),
      token_(std::move(token)),
      label_(std::move(label)),
      runner_(std::move(runner)),
      limits_(limits),
      pool_(pool),
      metrics_(metrics),
      on_finished_(std::move(on_finished)),
      created_(Clock::now()),
      inbox_(static_cast<size_t>(std::max(1, limits.max_queued_requests)), metrics->queue_depth, created_),
      outbox_(Outbox::kHistoryEstimates, &runner_->estimate_pool()),
      stream_changed_at_(created_) {}

bool SessionHost::TokenMatches(const std::string& token) const { return ConstantTimeEquals(token, token_); }

v1::SessionOpened SessionHost::OpenedLocked(bool resumed) const {
  v1::SessionOpened opened;
  opened.set_session_id(id_);
  opened.set_resume_token(token_);
  *opened.mutable_effective_config() = runner_->EffectiveConfig(label_);
  opened.set_backend(backend());
  opened.set_resumed(resumed);
  if (inbox_.last_sequence()) opened.set_last_sequence(*inbox_.last_sequence());
  opened.set_frames_processed(outbox_.frames());
  opened.set_session_ttl_s(limits_.ttl_s);
  opened.set_array_shape(runner_->info().array_shape);
  opened.set_localization(runner_->info().localization);
  return opened;
}

bool SessionHost::Attach(StreamSink* sink, bool resumed, const ResumePoint& resume) {
  MutexLock lock(&mutex_);
  if (closed_) return false;  // CloseSession or expiry raced the open/resume
  if (sink_ != nullptr && sink_ != sink) {
    StreamSink* old = sink_;
    sink_ = nullptr;
    if (!stream_ended_)
      old->End(grpc::Status(grpc::StatusCode::ABORTED, "session " + id_ + " was resumed on another stream"));
    Bump(metrics_->sessions_closed("replaced"));
  }
  sink_ = sink;
  stream_changed_at_ = Clock::now();  // the idle clock starts again
  stream_ended_ = input_done_ = draining_ = input_paused_ = false;
  auto opened = std::make_shared<v1::TrackResponse>();
  *opened->mutable_opened() = OpenedLocked(resumed);
  outbox_.Reattach(std::move(opened), resume);  // the old stream's write in flight goes first again
  PumpLocked();
  return true;
}

bool SessionHost::Offer(StreamSink* sink, const v1::TrackRequest& request, Clock::time_point received,
                        wire::DecodedBlock* scratch) {
  WorkItem item = runner_->Decode(request, received, scratch);  // outside the lock: the reader's work
  MutexLock lock(&mutex_);
  // Ended, replaced, draining or closed: blocks are no longer accepted.
  if (closed_ || sink_ != sink || stream_ended_ || input_done_) return false;
  const Inbox::Offered offered = inbox_.Offer(std::move(item), &scratch->samples);
  if (const Rejection* rejected = offered.rejected) {
    Bump(metrics_->rejections(rejected->reason));
    if (rejected->request == RequestKind::kBlock) {
      LogEvent("debug", "block_rejected",
               {{"session", id_}, {"sequence", std::to_string(rejected->sequence)}, {"reason", rejected->reason}});
    }
  }
  if (offered.gap) Bump(metrics_->gaps);
  ScheduleLocked();
  input_paused_ = !offered.room;
  return offered.room;
}

void SessionHost::InputDone(StreamSink* sink) {
  MutexLock lock(&mutex_);
  if (sink_ != sink || stream_ended_) return;
  input_done_ = true;
  PumpLocked();  // finishes now if everything is already written
}

void SessionHost::WriteDone(StreamSink* sink, bool ok) {
  MutexLock lock(&mutex_);
  // Replaced by a resume (which writes the response again) or closed: nothing to settle.
  if (sink_ != sink || !outbox_.writing()) return;
  if (!ok) {  // the stream broke: keep the response for a resume
    outbox_.Failed();
    EndStreamLocked(grpc::Status(grpc::StatusCode::CANCELLED, "write failed: stream broken"));
    return;
  }
  outbox_.Written();
  ScheduleLocked();  // the outbox shrank: processing may have paused on it
  PumpLocked();
}

void SessionHost::EndStream(StreamSink* sink, const grpc::Status& status) {
  MutexLock lock(&mutex_);
  if (sink_ == sink) EndStreamLocked(status);
}

bool SessionHost::Detach(StreamSink* sink) {
  MutexLock lock(&mutex_);
  if (sink_ == sink && sink != nullptr) {
    outbox_.Failed();  // a write never settled (none in practice: gRPC reports it first)
    sink_ = nullptr;
    stream_changed_at_ = Clock::now();
  }
  return !closed_;
}

void SessionHost::EndStreamLocked(const grpc::Status& status) {
  if (sink_ == nullptr || stream_ended_) return;
  stream_ended_ = true;
  sink_->End(status);
}

void SessionHost::ScheduleLocked() {
  if (scheduled_ || closed_ || inbox_.empty() || outbox_.waiting() >= limits_.max_outbox) return;
  scheduled_ = true;
  if (!pool_->Submit([self = shared_from_this()] { self->RunTurn(); })) scheduled_ = false;
}

void SessionHost::PumpLocked() {
  if (sink_ == nullptr || stream_ended_ || outbox_.writing()) return;
  if (ResponsePtr next = outbox_.TakeNext()) {
    const grpc::Status started = sink_->Write(*next, /*more_waiting=*/outbox_.waiting() > 0);
    if (!started.ok()) {  // cannot happen for a well-formed message; never loop on it
      outbox_.Failed();
      EndStreamLocked(
          grpc::Status(grpc::StatusCode::INTERNAL, "could not serialize a response: " + started.error_message()));
    }
    return;
  }
  if (!input_done_ || !IdleLocked()) return;
  if (sink_->Cancelled()) {  // broken, not finished: keep the session for a resume
    return EndStreamLocked(grpc::Status(grpc::StatusCode::CANCELLED, "stream cancelled"));
  }
  if (draining_) {
    return EndStreamLocked(grpc::Status(grpc::StatusCode::UNAVAILABLE,
                                        "server is shutting down; every accepted block was processed (last sequence "
                                        "in the last estimate); resume or reopen on another instance"));
  }
  // Finished: the session ends before the client sees OK, so nothing can find it after.
  if (on_finished_) on_finished_(InfoLocked(Clock::now(), limits_.ttl_s));
  CloseLocked(grpc::Status::OK);
}

void SessionHost::RunTurn() {
  for (int n = 0; n < kItemsPerTurn; ++n) {
    std::optional<WorkItem> item;
    {
      MutexLock lock(&mutex_);
      if (closed_ || outbox_.waiting() >= limits_.max_outbox) break;
      item = inbox_.Take();
      if (!item) break;
      running_ = true;
    }
    std::vector<ResponsePtr>& responses = turn_responses_;  // empty: moved out below
    if (const auto* rejected = std::get_if<Rejection>(&item->work)) {
      responses.push_back(RejectionResponse(*rejected));
    } else {
      runner_->Process(*item, Clock::now(), &track_, &responses);
    }
    MutexLock lock(&mutex_);
    running_ = false;
    inbox_.Done(*item);
    for (ResponsePtr& r : responses) outbox_.Push(std::move(r));
    responses.clear();  // keeps its capacity for the next item
    if (sink_ != nullptr && input_paused_ && inbox_.has_room()) {
      input_paused_ = false;
      if (!stream_ended_) sink_->ReadMore();
    }
    PumpLocked();
  }
  MutexLock lock(&mutex_);
  scheduled_ = false;
  ScheduleLocked();
  if (IdleLocked()) PumpLocked();
}

void SessionHost::Close(const grpc::Status& status) {
  MutexLock lock(&mutex_);
  CloseLocked(status);
}

void SessionHost::CloseLocked(const grpc::Status& status) {
  if (closed_) return;
  closed_ = true;
  inbox_.Clear();
  if (sink_ != nullptr) {
    StreamSink* sink = sink_;
    sink_ = nullptr;
    if (!stream_ended_) sink->End(status);
  }
}

void SessionHost::Drain() {
  MutexLock lock(&mutex_);
  if (sink_ == nullptr || stream_ended_) return;
  draining_ = input_done_ = true;
  PumpLocked();
}

bool SessionHost::Drained() const {
  MutexLock lock(&mutex_);
  return closed_ || (IdleLocked() && (sink_ == nullptr || outbox_.waiting() == 0));
}

bool SessionHost::attached() const {
  MutexLock lock(&mutex_);
  return sink_ != nullptr;
}

SessionHost::Expiry SessionHost::ExpiryAt(Clock::time_point now, double ttl_s, double idle_s) const {
  MutexLock lock(&mutex_);
  if (sink_ == nullptr) return Seconds(now - stream_changed_at_) > ttl_s ? Expiry::kDetached : Expiry::kNone;
  const double quiet_s = Seconds(now - std::max(stream_changed_at_, inbox_.last_accepted_at()));
  return idle_s > 0.0 && IdleLocked() && quiet_s > idle_s ? Expiry::kIdle : Expiry::kNone;
}

v1::SessionInfo SessionHost::Info(Clock::time_point now, double ttl_s) const {
  MutexLock lock(&mutex_);
  return InfoLocked(now, ttl_s);
}

v1::SessionInfo SessionHost::InfoLocked(Clock::time_point now, double ttl_s) const {
  v1::SessionInfo info;
  info.set_session_id(id_);
  info.set_label(label_);
  info.set_backend(backend());
  info.set_attached(sink_ != nullptr);
  info.set_channel_count(static_cast<uint32_t>(runner_info().channel_count));
  info.set_sample_rate_hz(config().sample_rate_hz);
  info.set_blocks_processed(inbox_.blocks_processed());
  info.set_frames_processed(outbox_.frames());
  info.set_rejections(inbox_.blocks_rejected());
  if (inbox_.last_sequence()) info.set_last_sequence(*inbox_.last_sequence());
  info.set_age_s(Seconds(now - created_));
  info.set_idle_s(Seconds(now - inbox_.last_accepted_at()));
  info.set_queued_blocks(static_cast<uint32_t>(inbox_.queued_blocks()));
  if (sink_ == nullptr) info.set_expires_in_s(std::max(0.0, ttl_s - Seconds(now - stream_changed_at_)));
  return info;
}

}  // namespace localizer::server
