// A detection session on a localizer server, with the same shape as the engine's
// ScanSession (engine/pipeline/scan_session.h): Process(scan) -> the track list after it.
//
// One Track stream opened with SessionConfig.detections; each Process writes the scan and
// reads until its TrackList arrives (one scan in flight at a time: the round trip is part
// of what Process measures). A scan the server refuses comes back as INVALID_ARGUMENT with
// the server's message ("INVALID_ARGUMENT: scan.detections[2].range_m is -3; ...") and the
// session goes on; a stream the server ends returns its status ("UNAVAILABLE: ...") and
// every later call fails the same way. Close half-closes and waits for the end.
// Not thread-safe: one caller at a time.
#pragma once

#include <grpcpp/channel.h>

#include <memory>
#include <string>

#include "clients/grpc/track_stream.h"
#include "engine/core/detection.h"
#include "engine/core/status.h"
#include "engine/pipeline/scan_session.h"

namespace localizer::client {

class RemoteScanSession {
 public:
  // A refused open returns the server's status with its code name first.
  static StatusOr<std::unique_ptr<RemoteScanSession>> Open(std::shared_ptr<grpc::Channel> channel,
                                                           const engine::DetectionSessionConfig& config,
                                                           const std::string& label, const std::string& session_key);
  ~RemoteScanSession();

  Status Process(const engine::Scan& scan, engine::ScanResult* out);
  // Wall time of the last Process: scan written -> its TrackList read, seconds.
  double last_round_trip_s() const { return last_round_trip_s_; }
  // The server's own figure for the last scan: received -> track list ready, seconds.
  double last_server_total_s() const { return last_server_total_s_; }
  const v1::SessionOpened& opened() const { return stream_->opened(); }
  // Half-close and wait for the stream's end; OK when the server ended it OK.
  Status Close();

 private:
  explicit RemoteScanSession(std::unique_ptr<TrackStream> stream) : stream_(std::move(stream)) {}
  Status Ended();  // the stream is over: its final status as a Status

  std::unique_ptr<TrackStream> stream_;
  uint64_t next_sequence_ = 1;
  double last_round_trip_s_ = 0.0;
  double last_server_total_s_ = 0.0;
  bool ended_ = false;
  Status end_status_;
};

}  // namespace localizer::client
