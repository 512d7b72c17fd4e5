// One Track stream: the gRPC callback reactor that reads requests, hands blocks to its
// session and writes the session's responses back (one write in flight at a time).
//
// Life of a stream:
//   read `open` -> SessionRegistry::Open, or `resume` -> SessionRegistry::Find; attach
//   read `block`s -> decode (here, on the gRPC thread: cheap) -> SessionHost::OfferLocked;
//     when the session's queue is full, reading pauses until a worker frees a slot, so a
//     fast client is held back by HTTP/2 flow control, never by memory.
//   client half-close -> finish with OK once every accepted block has produced its
//     responses and they are written; the session then closes.
//   stream broken or cancelled -> finish CANCELLED; the session stays, detached, for
//     the registry's TTL, its unwritten responses kept for a resume.
//   a request that does not parse -> finish INVALID_ARGUMENT; the session stays, detached
//     and resumable, as on a broken stream (a garbled request is never taken for a finish).
//
// The method is registered raw (ByteBuffer in and out) and the reactor parses requests
// itself: with typed messages gRPC 1.51 reports a request that fails to parse as
// OnReadDone(false), exactly like the client's half-close, so the two could not be told
// apart. Responses are serialized here as gRPC would (one serialization per write).
// Thread-safety: gRPC may run OnReadDone, OnWriteDone and OnCancel concurrently; once
// attached, every field below marked "host" is guarded by the session's mutex. Before
// attaching only the read path touches the reactor.
#pragma once

#include <memory>
#include <string>

#include <grpcpp/grpcpp.h>

#include "localizer/v1/localizer.grpc.pb.h"
#include "server/service/session_host.h"
#include "server/service/session_registry.h"
#include "server/service/stream_sink.h"

namespace localizer::server {

class TrackReactor final : public grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>,
                           public StreamSink {
 public:
  TrackReactor(grpc::CallbackServerContext* context, SessionRegistry* registry, ServiceMetrics* metrics);

  // grpc::ServerBidiReactor
  void OnReadDone(bool ok) override;
  void OnWriteDone(bool ok) override;
  void OnCancel() override;
  void OnDone() override;

  // StreamSink (called with the session's mutex held)
  void OutputReadyLocked() override;
  void InputSpaceLocked() override;
  void EndLocked(const grpc::Status& status) override;
  void DrainLocked() override;
  ResponsePtr TakeInFlightLocked() override;

 private:
  void HandleOpen(const v1::SessionConfig& config);
  void HandleResume(const v1::ResumeSession& resume);
  // False (the stream finished FAILED_PRECONDITION) when no open/resume came first.
  bool NeedsSession(const char* what);
  // After an Offer*Locked: read on, or pause reading until the session has room.
  void OfferLocked(bool room);
  void HandleBlock();
  void HandleImu();   // moving-array sessions: IMU samples in order with the blocks
  void HandleScan();  // detection sessions: one scan of plots -> a track list
  void Attach(std::shared_ptr<SessionHost> host, bool resumed, std::optional<uint64_t> last_frame,
              bool received_none = false);
  // Ends the stream once; before attaching (no lock needed) or with the host's lock held.
  void FinishOnce(const grpc::Status& status);
  // The stream broke or was cancelled: end it and leave the session resumable.
  void CancelLocked();
  void ReadNext();
  // A request that did not parse: end the stream INVALID_ARGUMENT, keep the session.
  void ParseFailed(size_t bytes);

  grpc::CallbackServerContext* const context_;
  SessionRegistry* const registry_;
  ServiceMetrics* const metrics_;
  std::string peer_;

  grpc::ByteBuffer read_buffer_;         // read path only: the request as received
  v1::TrackRequest request_;             // read path only: read_buffer_ parsed
  grpc::ByteBuffer write_buffer_;        // host: writing_ serialized
  wire::DecodedBlock decoded_;           // read path only
  std::shared_ptr<SessionHost> host_;    // set once by the read path, before attaching

  ResponsePtr writing_;                  // host: the response in flight, if any
  bool finished_ = false;                // host: Finish called
  bool finished_clean_ = false;          // host: finished OK after the client's half-close
  bool input_done_ = false;              // host: the client half-closed
  bool read_paused_ = false;             // host: waiting for queue space
  bool cancelled_ = false;               // host: OnCancel ran or a write failed
  bool draining_ = false;                // host: the server is shutting down
};

}  // namespace localizer::server
