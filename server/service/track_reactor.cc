#include "server/service/track_reactor.h"

#include "server/service/log.h"
#include "wire/status_wire.h"
#include "wire/tsan_annotations.h"

namespace localizer::server {

TrackReactor::TrackReactor(grpc::CallbackServerContext* context, SessionRegistry* registry, ServiceMetrics* metrics)
    : context_(context), registry_(registry), metrics_(metrics), peer_(context->peer()) {
  StartRead(&read_buffer_);
  // The Tsan* calls here and below tell ThreadSanitizer what the completion queue of
  // Debian's libgrpc (not built with TSan) orders: whatever a thread did before it started an
  // operation happens before the reaction to it, which may run on another thread. One
  // address per kind of operation: the read buffer (StartRead -> OnReadDone), the write
  // buffer (StartWrite -> OnWriteDone), the reactor (built -> OnCancel, Finish -> OnDone).
  // Elsewhere the release comes before the Start (its reaction may run before it returns);
  // here after: in the constructor gRPC only notes the read, and starts it once the reactor
  // is bound, after this returns.
  wire::TsanRelease(this);
  wire::TsanRelease(&read_buffer_);
}

void TrackReactor::FinishOnce(const grpc::Status& status) {
  MutexLock lock(&mutex_);
  if (finished_) return;
  finished_ = true;
  wire::TsanRelease(this);
  Finish(status);
}

void TrackReactor::ReadNext() {
  MutexLock lock(&mutex_);
  if (finished_) return;
  wire::TsanRelease(&read_buffer_);
  StartRead(&read_buffer_);
}

void TrackReactor::EndStream(const grpc::Status& status) {
  if (SessionHost* host = Host()) host->EndStream(this, status);
  FinishOnce(status);  // nothing more when the session ended it (or had ended it before)
}

void TrackReactor::ParseFailed(size_t bytes) {
  SessionHost* host = Host();
  const grpc::Status status(grpc::StatusCode::INVALID_ARGUMENT,
                            "TrackRequest of " + std::to_string(bytes) +
                                " bytes could not be parsed (not a serialized localizer.v1.TrackRequest)" +
                                (host ? "; session " + host->id() + " stays open for a resume" : std::string()));
  LogEvent("info", "request_unparseable",
           {{"peer", peer_}, {"bytes", std::to_string(bytes)}, {"session", host ? host->id() : std::string()}});
  EndStream(status);  // like a broken stream: the session detaches (OnDone) and can be resumed
}

void TrackReactor::OnReadDone(bool ok) {
  wire::TsanAcquire(&read_buffer_);
  if (!ok) {  // the client half-closed, or the stream broke (a parse failure is handled below)
    SessionHost* host = Host();
    if (!host) return FinishOnce(grpc::Status::OK);
    if (context_->IsCancelled()) {  // broken, not half-closed: keep the session for a resume
      return EndStream(grpc::Status(grpc::StatusCode::CANCELLED, "stream cancelled"));
    }
    return host->InputDone(this);  // the session finishes the stream once all is written
  }
  const size_t bytes = read_buffer_.Length();
  const grpc::Status parsed = grpc::SerializationTraits<v1::TrackRequest>::Deserialize(&read_buffer_, &request_);
  read_buffer_.Clear();
  if (!parsed.ok()) return ParseFailed(bytes);
  switch (request_.kind_case()) {
    case v1::TrackRequest::kOpen:
      return HandleOpen(request_.open());
    case v1::TrackRequest::kResume:
      return HandleResume(request_.resume());
    case v1::TrackRequest::kBlock:
      return HandleInput("a block");
    case v1::TrackRequest::kImu:
      return HandleInput("an imu batch");
    case v1::TrackRequest::kScan:
      return HandleInput("a scan");
    default:
      break;
  }
  EndStream(grpc::Status(grpc::StatusCode::INVALID_ARGUMENT, "TrackRequest has no open, resume, block, imu or scan"));
}

void TrackReactor::HandleOpen(const v1::SessionConfig& config) {
  if (SessionHost* host = Host()) {
    return EndStream(grpc::Status(grpc::StatusCode::FAILED_PRECONDITION,
                                  "this stream already has session " + host->id() + "; open a new stream"));
  }
  auto host = registry_->Open(config);
  if (!host.ok()) {
    LogEvent("info", "open_refused", {{"peer", peer_}, {"status", host.status().ToString()}});
    return FinishOnce(wire::ToGrpcStatus(host.status()));
  }
  if (metrics_->opened != nullptr) metrics_->opened->Increment();
  LogEvent("info", "session_open",
           {{"session", (*host)->id()},
            {"peer", peer_},
            {"label", config.label()},
            {"backend", (*host)->backend()},
            {"sensors", std::to_string(config.array().sensors_m_size())},
            {"sample_rate_hz", std::to_string(config.sample_rate_hz())}});
  Attach(std::move(host).value(), false, ResumePoint{});
}

void TrackReactor::HandleResume(const v1::ResumeSession& resume) {
  if (Host() != nullptr) {
    return EndStream(grpc::Status(grpc::StatusCode::FAILED_PRECONDITION, "this stream already has a session"));
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
  ResumePoint point;
  if (resume.has_last_frame_received()) point.last_frame_received = resume.last_frame_received();
  point.received_none = resume.received_none();
  Attach(std::move(host).value(), true, point);
}

void TrackReactor::Attach(std::shared_ptr<SessionHost> host, bool resumed, const ResumePoint& resume) {
  SessionHost* const attached = host.get();
  owner_ = std::move(host);
  host_.store(attached, std::memory_order_release);
  if (!attached->Attach(this, resumed, resume)) {
    // Closed between Find and here (CloseSession or expiry raced us).
    return FinishOnce(grpc::Status(grpc::StatusCode::NOT_FOUND, "session " + attached->id() + " was just closed"));
  }
  ReadNext();
}

void TrackReactor::HandleInput(const char* what) {
  SessionHost* host = Host();
  if (host == nullptr) {
    return FinishOnce(
        grpc::Status(grpc::StatusCode::FAILED_PRECONDITION,
                     std::string(what) + " arrived before open or resume; the first request must open a session"));
  }
  // False: the inbox is full (the session calls ReadMore when it has room) or the stream
  // takes no more input (it is ending).
  if (host->Offer(this, request_, Clock::now(), &decoded_)) ReadNext();
}

grpc::Status TrackReactor::Write(const v1::TrackResponse& response, bool more_waiting) {
  // No lock of ours: the session calls this with its lock held, one write at a time, and never
  // after it ended the stream (every end after attaching goes through the session).
  bool own_buffer = false;
  write_buffer_.Clear();  // the previous write's bytes (gRPC holds its own reference)
  grpc::Status serialized =
      grpc::SerializationTraits<v1::TrackResponse>::Serialize(response, &write_buffer_, &own_buffer);
  if (!serialized.ok()) return serialized;
  // More already waiting: let gRPC hold this one and send them in one flush.
  grpc::WriteOptions options;
  if (more_waiting) options.set_buffer_hint();
  wire::TsanRelease(&write_buffer_);
  StartWrite(&write_buffer_, options);
  return grpc::Status::OK;
}

void TrackReactor::ReadMore() { ReadNext(); }

void TrackReactor::End(const grpc::Status& status) { FinishOnce(status); }

void TrackReactor::OnWriteDone(bool ok) {
  wire::TsanAcquire(&write_buffer_);
  if (SessionHost* host = Host()) host->WriteDone(this, ok);
}

void TrackReactor::OnCancel() {
  wire::TsanAcquire(this);
  SessionHost* host = Host();
  if (host == nullptr) return;  // OnDone follows; nothing attached
  EndStream(grpc::Status(grpc::StatusCode::CANCELLED, "stream cancelled"));
}

void TrackReactor::OnDone() {
  // After Finish and after every other reaction returned.
  wire::TsanAcquire(this);
  wire::TsanAcquire(&read_buffer_);
  wire::TsanAcquire(&write_buffer_);
  {
    MutexLock lock(&mutex_);  // waits for a FinishOnce still inside the lock on another thread
  }
  // Every other reaction has returned: owner_ is read without a race. Detach takes the
  // session's lock: any session call into this sink has returned after it.
  const std::shared_ptr<SessionHost>& host = owner_;
  if (host && host->Detach(this)) LogEvent("info", "session_detached", {{"session", host->id()}, {"peer", peer_}});
  delete this;
}

}  // namespace localizer::server
