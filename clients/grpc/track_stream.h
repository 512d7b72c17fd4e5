// One `Track` stream of the Localizer service, on the synchronous gRPC API.
//
// Lifecycle (the proto's Track comment is the contract):
//   Open / Resume   send `open` (or `resume`) and wait for the `opened` response. A stream
//                   the server ends instead (bad config, wrong token, no capacity, server
//                   unreachable) is returned as a Status whose message starts with the gRPC
//                   code name: "INVALID_ARGUMENT: array.sensors_m has 3 sensors; ...".
//   Write           send blocks (WriteImu: IMU batches of a moving array; WriteScan: scans
//                   of a detection session); false once the stream is broken or finished.
//   Read            the responses after `opened`, in order (estimate, rejected, gap, tracks); false
//                   when the server has ended the stream.
//   WritesDone      half-close: "finished". The server processes every accepted block, sends
//                   the remaining estimates and ends the stream OK; the session closes.
//   Finish          after Read returned false: the stream's final status (a proxy's reset
//                   after its instance died reads as UNAVAILABLE: FromProxyReset).
//   Cancel          abandon the stream (context TryCancel). The server keeps the session
//                   detached and resumable for its TTL (SessionOpened.session_ttl_s).
//
// Threads: one writer thread (Write, then WritesDone) and one reader thread (Read, then
// Finish) may run concurrently, as gRPC's sync streams allow; no two threads may Write (or
// Read) at once. Cancel is safe from any thread at any time. Finish must come after the
// writer is done and Read has returned false. Destroying a stream that was not finished
// cancels it first.
//
// Every call carries the metadata "x-localizer-session-key" (connection.h): the key given,
// or a random one when it is empty. A client resuming through a session-affine proxy must
// pass the key it opened with (session_key()).
#pragma once

#include <grpcpp/channel.h>
#include <grpcpp/client_context.h>
#include <grpcpp/support/sync_stream.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "engine/core/status.h"
#include "localizer/v1/localizer.grpc.pb.h"
#include "localizer/v1/localizer.pb.h"

namespace localizer::client {

class TrackStream {
 public:
  // A new session with `config`.
  static StatusOr<std::unique_ptr<TrackStream>> Open(std::shared_ptr<grpc::Channel> channel,
                                                     const v1::SessionConfig& config, const std::string& session_key);
  // An existing, detached session. `last_frame_received`: the frame_index of the last
  // estimate this client holds; the server resends later ones it still has. nullopt: this
  // client holds no estimate of the session (sent as ResumeSession.received_none), so the
  // server resends every estimate it still has, frame 0 included.
  static StatusOr<std::unique_ptr<TrackStream>> Resume(std::shared_ptr<grpc::Channel> channel,
                                                       const std::string& session_id, const std::string& resume_token,
                                                       std::optional<uint64_t> last_frame_received,
                                                       const std::string& session_key);

  ~TrackStream();
  TrackStream(const TrackStream&) = delete;
  TrackStream& operator=(const TrackStream&) = delete;

  // The server's answer to open/resume: session id, resume token, effective config, backend.
  const v1::SessionOpened& opened() const { return opened_; }
  const std::string& session_key() const { return session_key_; }

  bool Write(const v1::SampleBlock& block);
  bool WriteImu(const v1::ImuBatch& batch);  // moving-array sessions (before the blocks it covers)
  bool WriteScan(const v1::Scan& scan);      // detection sessions: answered by a `tracks` response
  bool Read(v1::TrackResponse* response);
  void WritesDone();
  grpc::Status Finish();
  void Cancel();

 private:
  TrackStream(std::shared_ptr<grpc::Channel> channel, std::string session_key);
  // Sends `first` (open or resume) and reads `opened`.
  Status Start(const v1::TrackRequest& first);
  // Cancels, drains and finishes; returns the final status.
  grpc::Status Abandon();

  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::Localizer::Stub> stub_;
  std::string session_key_;
  grpc::ClientContext context_;
  std::unique_ptr<grpc::ClientReaderWriter<v1::TrackRequest, v1::TrackResponse>> stream_;
  v1::SessionOpened opened_;
  bool finished_ = false;  // Finish was called (by the reader thread, or before returning)
};

}  // namespace localizer::client
