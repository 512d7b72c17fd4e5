#include "clients/grpc/remote_scan_session.h"

#include <chrono>

#include "wire/config_wire.h"
#include "wire/scan_wire.h"
#include "wire/status_wire.h"

namespace localizer::client {

StatusOr<std::unique_ptr<RemoteScanSession>> RemoteScanSession::Open(std::shared_ptr<grpc::Channel> channel,
                                                                     const engine::DetectionSessionConfig& config,
                                                                     const std::string& label,
                                                                     const std::string& session_key) {
  auto stream = TrackStream::Open(std::move(channel), wire::ConfigToProto(config, label), session_key);
  if (!stream.ok()) return stream.status();
  return std::unique_ptr<RemoteScanSession>(new RemoteScanSession(std::move(stream).value()));
}

RemoteScanSession::~RemoteScanSession() {
  if (!ended_) stream_->Cancel();
}

Status RemoteScanSession::Ended() {
  if (!ended_) {
    ended_ = true;
    const grpc::Status status = stream_->Finish();
    end_status_ =
        status.ok() ? FailedPrecondition("the server ended the detection session") : wire::FromGrpcStatus(status);
  }
  return end_status_;
}

Status RemoteScanSession::Process(const engine::Scan& scan, engine::ScanResult* out) {
  if (ended_) return end_status_;
  const uint64_t sequence = next_sequence_++;
  v1::Scan request;
  wire::EncodeScan(scan, sequence, &request);
  const auto start = std::chrono::steady_clock::now();
  if (!stream_->WriteScan(request)) return Ended();
  v1::TrackResponse response;
  while (stream_->Read(&response)) {
    if (response.has_rejected() && response.rejected().sequence() == sequence) {
      last_round_trip_s_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      return InvalidArgument(response.rejected().code() + ": " + response.rejected().message());
    }
    if (response.has_tracks() && response.tracks().sequence() == sequence) {
      last_round_trip_s_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      last_server_total_s_ = response.tracks().total_s();
      *out = wire::TrackListFromProto(response.tracks());
      return Status::Ok();
    }
  }
  return Ended();
}

Status RemoteScanSession::Close() {
  if (ended_) return end_status_;
  stream_->WritesDone();
  v1::TrackResponse ignored;
  while (stream_->Read(&ignored)) {
  }
  ended_ = true;
  const grpc::Status status = stream_->Finish();
  end_status_ = wire::FromGrpcStatus(status);
  return end_status_;
}

}  // namespace localizer::client
