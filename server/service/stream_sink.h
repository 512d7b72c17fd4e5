// What a session needs from the stream attached to it (the Track reactor implements it).
// Every method is called with the session's mutex held, must not block, and must not call
// back into the session.
#pragma once

#include <memory>

#include <grpcpp/support/status.h>

#include "localizer/v1/localizer.pb.h"

namespace localizer::server {

class StreamSink {
 public:
  virtual ~StreamSink() = default;
  // The outbox has something to write, or the session became idle (all input processed).
  virtual void OutputReadyLocked() = 0;
  // The session's queue has room again: a paused reader may read on.
  virtual void InputSpaceLocked() = 0;
  // The session is ending (closed, replaced by a resume elsewhere, server draining): end
  // the stream with `status`. The session forgets the sink before calling this.
  virtual void EndLocked(const grpc::Status& status) = 0;
  // The response being written now, if any; the sink forgets it (its completion will not
  // touch the session). Used when a resume replaces this stream.
  virtual std::shared_ptr<const v1::TrackResponse> TakeInFlightLocked() = 0;
  // The server is shutting down: stop reading, write what the accepted blocks produce,
  // then end the stream with UNAVAILABLE.
  virtual void DrainLocked() = 0;
};

}  // namespace localizer::server
