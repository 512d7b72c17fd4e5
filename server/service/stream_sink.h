// What a session host needs from the stream attached to it (the Track reactor implements it).
//
// The host decides, the sink acts. Every method here is called by the SessionHost with the
// host's lock held; an implementation must not block (it may take a lock of its own, held
// briefly and never while calling the host) and must not call back into the host -- what
// happens later (a write completes, the client half-closes, the stream is cancelled) it
// reports through the host's public methods, from its own callbacks, holding no lock.
// See session_host.h for the whole contract.
#pragma once

#include <grpcpp/support/status.h>

#include "localizer/v1/localizer.pb.h"

namespace localizer::server {

class StreamSink {
 public:
  virtual ~StreamSink() = default;
  // Start writing `response` (the host hands out one at a time: the next comes after
  // SessionHost::WriteDone). `more_waiting`: further responses are ready, so the write may
  // be held back to share a flush with them. A status other than OK means nothing was
  // started (the response could not be serialized); the host then ends the stream.
  virtual grpc::Status Write(const v1::TrackResponse& response, bool more_waiting) = 0;
  // The inbox has room again after Offer said "stop reading": read the next request.
  virtual void ReadMore() = 0;
  // End the stream with `status` (called once per stream). The sink may still report a
  // write in flight (WriteDone) and must still Detach.
  virtual void End(const grpc::Status& status) = 0;
  // The client cancelled the call or the connection broke (gRPC's IsCancelled).
  virtual bool Cancelled() const = 0;
};

}  // namespace localizer::server
