// One Track stream: the gRPC callback reactor that reads requests, hands them to its
// session and writes what the session hands it (one write in flight at a time).
//
// Life of a stream:
//   read `open` -> SessionRegistry::Open, or `resume` -> SessionRegistry::Find; attach
//   read `block`s, `imu` batches, `scan`s -> SessionHost::Offer (the session's runner
//     decodes them here, on the gRPC thread: cheap); when the session's inbox is full,
//     reading pauses until the session asks for more (ReadMore), so a fast client is held
//     back by HTTP/2 flow control, never by memory.
//   client half-close -> SessionHost::InputDone; the session ends the stream OK once every
//     accepted request has produced its responses and they are written, and closes.
//   stream broken or cancelled -> ends CANCELLED; the session stays, detached, for the
//     registry's TTL, its unwritten responses kept for a resume.
//   a request that does not parse -> ends INVALID_ARGUMENT; the session stays, detached
//     and resumable, as on a broken stream (a garbled request is never taken for a finish).
//
// The stream contract (session_host.h, stream_sink.h): the session decides what to write
// and when the stream ends; the reactor acts on it (StreamSink: Write, ReadMore, End, called
// with the session's lock held) and reports what gRPC tells it (OnWriteDone, OnReadDone,
// OnCancel, OnDone) through the session's public methods. The reactor never holds its own
// lock while calling the session, and never calls the session from a StreamSink method.
//
// The method is registered raw (ByteBuffer in and out) and the reactor parses requests
// itself: with typed messages gRPC 1.51 reports a request that fails to parse as
// OnReadDone(false), exactly like the client's half-close, so the two could not be told
// apart. Responses are serialized here as gRPC would (one serialization per write).
//
// Thread-safety: gRPC may run OnReadDone, OnWriteDone and OnCancel concurrently, and the
// session calls the StreamSink methods from its worker. `mutex_` (taken after the session's
// lock, never before it) orders Finish against StartRead. The attached session is published
// once by the read path (an atomic pointer; its owning reference is read again only by
// OnDone, after every other reaction). The read path's buffers are touched by one read at a
// time; the write buffer by Write, which the session calls for one write at a time, with its
// lock held, and never after it ended the stream.
#pragma once

#include <grpcpp/grpcpp.h>

#include <atomic>
#include <memory>
#include <optional>
#include <string>

#include "localizer/v1/localizer.grpc.pb.h"
#include "server/service/session_host.h"
#include "server/service/session_registry.h"
#include "server/service/stream_sink.h"
#include "server/sync/mutex.h"
#include "wire/block_wire.h"

namespace localizer::server {

class TrackReactor final : public grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>, public StreamSink {
 public:
  TrackReactor(grpc::CallbackServerContext* context, SessionRegistry* registry, ServiceMetrics* metrics);

  // grpc::ServerBidiReactor
  void OnReadDone(bool ok) override EXCLUDES(mutex_);
  void OnWriteDone(bool ok) override EXCLUDES(mutex_);
  void OnCancel() override EXCLUDES(mutex_);
  void OnDone() override EXCLUDES(mutex_);

  // StreamSink (called by the session, its lock held)
  grpc::Status Write(const v1::TrackResponse& response, bool more_waiting) override;
  void ReadMore() override EXCLUDES(mutex_);
  void End(const grpc::Status& status) override EXCLUDES(mutex_);
  bool Cancelled() const override { return context_->IsCancelled(); }

 private:
  // The attached session, or null before open/resume (it never changes once set).
  SessionHost* Host() const { return host_.load(std::memory_order_acquire); }
  void HandleOpen(const v1::SessionConfig& config) EXCLUDES(mutex_);
  void HandleResume(const v1::ResumeSession& resume) EXCLUDES(mutex_);
  // A block, IMU batch or scan: to the session (`what` names it if none is attached).
  void HandleInput(const char* what) EXCLUDES(mutex_);
  void Attach(std::shared_ptr<SessionHost> host, bool resumed, const ResumePoint& resume) EXCLUDES(mutex_);
  // Ends the stream through the session when one is attached (which leaves it resumable),
  // else directly.
  void EndStream(const grpc::Status& status) EXCLUDES(mutex_);
  // Calls Finish once; later calls do nothing.
  void FinishOnce(const grpc::Status& status) EXCLUDES(mutex_);
  void ReadNext() EXCLUDES(mutex_);  // unless finished
  // A request that did not parse: end the stream INVALID_ARGUMENT, keep the session.
  void ParseFailed(size_t bytes) EXCLUDES(mutex_);

  grpc::CallbackServerContext* const context_;
  SessionRegistry* const registry_;
  ServiceMetrics* const metrics_;
  const std::string peer_;

  grpc::ByteBuffer read_buffer_;   // read path: the request as received
  v1::TrackRequest request_;       // read path: read_buffer_ parsed
  wire::DecodedBlock decoded_;     // read path: the session's runner decodes blocks into it
  grpc::ByteBuffer write_buffer_;  // Write: the response in flight, serialized

  std::shared_ptr<SessionHost> owner_;       // set once by the read path, then read by OnDone
  std::atomic<SessionHost*> host_{nullptr};  // owner_, published for the other threads
  mutable Mutex mutex_;
  bool finished_ GUARDED_BY(mutex_) = false;  // Finish called
};

}  // namespace localizer::server
