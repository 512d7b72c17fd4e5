#include "server/service/track_reactor.h"

#include "server/service/log.h"
#include "wire/status_wire.h"

namespace localizer::server {

TrackReactor::TrackReactor(grpc::CallbackServerContext* context, SessionRegistry* registry,
                           ServiceMetrics* metrics)
    : context_(context), registry_(registry), metrics_(metrics), peer_(context->peer()) {
  StartRead(&read_buffer_);
}

void TrackReactor::FinishOnce(const grpc::Status& status) {
  if (finished_) return;
  finished_ = true;
  Finish(status);
}

void TrackReactor::ReadNext() {
  if (!finished_) StartRead(&read_buffer_);
}

void TrackReactor::ParseFailed(size_t bytes) {
  const grpc::Status status(grpc::StatusCode::INVALID_ARGUMENT,
                            "TrackRequest of " + std::to_string(bytes) +
                                " bytes could not be parsed (not a serialized localizer.v1.TrackRequest)" +
                                (host_ ? "; session " + host_->id() + " stays open for a resume" : std::string()));
  LogEvent("info", "request_unparseable",
           {{"peer", peer_}, {"bytes", std::to_string(bytes)}, {"session", host_ ? host_->id() : std::string()}});
  if (!host_) return FinishOnce(status);
  std::lock_guard<std::mutex> lock(host_->mutex());
  // Like a broken stream: the session detaches (OnDone) and can be resumed.
  cancelled_ = true;
  FinishOnce(status);
}

void TrackReactor::OnReadDone(bool ok) {
  if (ok) {
    const size_t bytes = read_buffer_.Length();
    const grpc::Status parsed = grpc::SerializationTraits<v1::TrackRequest>::Deserialize(&read_buffer_, &request_);
    read_buffer_.Clear();
    if (!parsed.ok()) return ParseFailed(bytes);
  }
  if (!ok) {  // the client half-closed, or the stream broke (a parse failure is handled above)
    if (!host_) {
      FinishOnce(grpc::Status::OK);
      return;
    }
    std::lock_guard<std::mutex> lock(host_->mutex());
    if (context_->IsCancelled()) {  // broken, not half-closed: keep the session for a resume
      return CancelLocked();
    }
    input_done_ = true;
    OutputReadyLocked();  // finishes now if everything is already written
    return;
  }
  switch (request_.kind_case()) {
    case v1::TrackRequest::kOpen: return HandleOpen(request_.open());
    case v1::TrackRequest::kResume: return HandleResume(request_.resume());
    case v1::TrackRequest::kBlock: return HandleBlock();
    case v1::TrackRequest::kImu: return HandleImu();
    case v1::TrackRequest::kScan: return HandleScan();
    default: break;
  }
  const grpc::Status status(grpc::StatusCode::INVALID_ARGUMENT, "TrackRequest has no open, resume, block, imu or scan");
  if (!host_) return FinishOnce(status);
  std::lock_guard<std::mutex> lock(host_->mutex());
  FinishOnce(status);
}

void TrackReactor::HandleOpen(const v1::SessionConfig& config) {
  if (host_) {
    std::lock_guard<std::mutex> lock(host_->mutex());
    return FinishOnce(grpc::Status(grpc::StatusCode::FAILED_PRECONDITION,
                                   "this stream already has session " + host_->id() + "; open a new stream"));
  }
  auto host = registry_->Open(config);
  if (!host.ok()) {
    LogEvent("info", "open_refused", {{"peer", peer_}, {"status", host.status().ToString()}});
    return FinishOnce(wire::ToGrpcStatus(host.status()));
  }
  if (metrics_->opened != nullptr) metrics_->opened->Increment();
  LogEvent("info", "session_open",
           {{"session", (*host)->id()}, {"peer", peer_}, {"label", config.label()}, {"backend", (*host)->backend()},
            {"sensors", std::to_string(config.array().sensors_m_size())},
            {"sample_rate_hz", std::to_string(config.sample_rate_hz())}});
  Attach(std::move(host).value(), false, std::nullopt);
}

void TrackReactor::HandleResume(const v1::ResumeSession& resume) {
  if (host_) {
    std::lock_guard<std::mutex> lock(host_->mutex());
    return FinishOnce(grpc::Status(grpc::StatusCode::FAILED_PRECONDITION, "this stream already has a session"));
  }
  if (resume.received_none() && resume.has_last_frame_received()) {
    return FinishOnce(grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                                   "resume.received_none and resume.last_frame_received are exclusive: send one"));
  }
  auto host = registry_->Find(resume.session_id(), resume.resume_token());
  if (!host.ok()) {
    LogEvent("info", "resume_refused", {{"peer", peer_}, {"status", host.status().ToString()}});
    return FinishOnce(wire::ToGrpcStatus(host.status()));
  }
  if (metrics_->resumed != nullptr) metrics_->resumed->Increment();
  LogEvent("info", "session_resume", {{"session", (*host)->id()}, {"peer", peer_}});
  std::optional<uint64_t> last_frame;
  if (resume.has_last_frame_received()) last_frame = resume.last_frame_received();
  Attach(std::move(host).value(), true, last_frame, resume.received_none());
}

void TrackReactor::Attach(std::shared_ptr<SessionHost> host, bool resumed, std::optional<uint64_t> last_frame,
                          bool received_none) {
  host_ = std::move(host);
  std::lock_guard<std::mutex> lock(host_->mutex());
  if (host_->ClosedLocked()) {
    // Closed between Find and here (CloseSession or expiry raced us).
    return FinishOnce(grpc::Status(grpc::StatusCode::NOT_FOUND, "session " + host_->id() + " was just closed"));
  }
  host_->AttachLocked(this, resumed, last_frame, received_none);
  ReadNext();
}

bool TrackReactor::NeedsSession(const char* what) {
  if (host_) return true;
  FinishOnce(grpc::Status(grpc::StatusCode::FAILED_PRECONDITION,
                          std::string(what) + " arrived before open or resume; the first request must open a session"));
  return false;
}

void TrackReactor::OfferLocked(bool room) {
  if (room) {
    ReadNext();
  } else {
    read_paused_ = true;  // the session's queue is full: InputSpaceLocked resumes reading
  }
}

void TrackReactor::HandleBlock() {
  if (!NeedsSession("a block")) return;
  const auto received = Clock::now();
  const v1::SampleBlock& block = request_.block();
  std::string reason;
  const Status decoded = wire::DecodeBlock(block, host_->block_limits(), &decoded_, &reason);
  std::lock_guard<std::mutex> lock(host_->mutex());
  if (finished_ || input_done_) return;  // draining: blocks are no longer accepted
  OfferLocked(host_->OfferLocked(&decoded_, decoded, reason, block.sequence(), received));
}

void TrackReactor::HandleImu() {
  if (!NeedsSession("an imu batch")) return;
  const auto received = Clock::now();
  auto decoded = wire::DecodeImuBatch(request_.imu());
  std::lock_guard<std::mutex> lock(host_->mutex());
  if (finished_ || input_done_) return;
  OfferLocked(host_->OfferImuLocked(std::move(decoded), request_.imu().sequence(), received));
}

void TrackReactor::HandleScan() {
  if (!NeedsSession("a scan")) return;
  const auto received = Clock::now();
  auto decoded = wire::DecodeScan(request_.scan());
  std::lock_guard<std::mutex> lock(host_->mutex());
  if (finished_ || input_done_) return;
  OfferLocked(host_->OfferScanLocked(std::move(decoded), request_.scan().sequence(), received));
}

void TrackReactor::InputSpaceLocked() {
  if (!read_paused_ || finished_) return;
  read_paused_ = false;
  StartRead(&read_buffer_);
}

void TrackReactor::OutputReadyLocked() {
  if (finished_ || writing_) return;
  writing_ = host_->NextOutputLocked();
  if (writing_) {
    // More already waiting: let gRPC hold this one and send both in one flush.
    grpc::WriteOptions options;
    if (host_->HasOutputLocked()) options.set_buffer_hint();
    bool own_buffer = false;
    write_buffer_.Clear();  // the previous write's bytes (gRPC holds its own reference)
    const grpc::Status serialized =
        grpc::SerializationTraits<v1::TrackResponse>::Serialize(*writing_, &write_buffer_, &own_buffer);
    if (!serialized.ok()) {  // cannot happen for a well-formed message; never loop on it
      host_->RequeueLocked(std::move(writing_));
      writing_.reset();
      FinishOnce(grpc::Status(grpc::StatusCode::INTERNAL, "could not serialize a response: " +
                                                              serialized.error_message()));
      return;
    }
    StartWrite(&write_buffer_, options);
    return;
  }
  if (input_done_ && host_->IdleLocked()) {
    if (context_->IsCancelled()) {
      return CancelLocked();
    }
    if (draining_) {
      FinishOnce(grpc::Status(grpc::StatusCode::UNAVAILABLE,
                              "server is shutting down; every accepted block was processed (last sequence in the "
                              "last estimate); resume or reopen on another instance"));
      return;
    }
    // Finished: the session ends before the client sees OK, so nothing can find it after.
    finished_clean_ = true;
    registry_->Forget(host_->id(), "finished");
    host_->CloseLocked(grpc::Status::OK);  // its EndLocked finishes this stream with OK
    FinishOnce(grpc::Status::OK);
  }
}

ResponsePtr TrackReactor::TakeInFlightLocked() { return std::move(writing_); }

void TrackReactor::DrainLocked() {
  draining_ = true;
  input_done_ = true;
  OutputReadyLocked();
}

void TrackReactor::OnWriteDone(bool ok) {
  std::lock_guard<std::mutex> lock(host_->mutex());
  ResponsePtr written = std::move(writing_);
  writing_.reset();
  if (!written) return;  // taken by a resume on another stream, which writes it again
  if (!ok) {  // the stream broke: keep the response for a resume
    host_->RequeueLocked(std::move(written));
    cancelled_ = true;
    FinishOnce(grpc::Status(grpc::StatusCode::CANCELLED, "write failed: stream broken"));
    return;
  }
  host_->MarkWrittenLocked(written);
  OutputReadyLocked();
}

void TrackReactor::EndLocked(const grpc::Status& status) {
  // The session forgot this stream already; a write in flight completes on its own.
  FinishOnce(status);
}

void TrackReactor::OnCancel() {
  if (!host_) return;  // OnDone follows; nothing attached
  std::lock_guard<std::mutex> lock(host_->mutex());
  CancelLocked();
}

void TrackReactor::CancelLocked() {
  cancelled_ = true;
  FinishOnce(grpc::Status(grpc::StatusCode::CANCELLED, "stream cancelled"));
}

void TrackReactor::OnDone() {
  if (host_) {
    bool detached = false;
    {
      std::lock_guard<std::mutex> lock(host_->mutex());
      host_->DetachLocked(this);
      detached = !host_->ClosedLocked();
    }
    if (detached) LogEvent("info", "session_detached", {{"session", host_->id()}, {"peer", peer_}});
  }
  delete this;
}

}  // namespace localizer::server
