#include "clients/grpc/track_stream.h"

#include <utility>

#include "clients/grpc/connection.h"
#include "wire/status_wire.h"

namespace localizer::client {

namespace {

const char* ResponseKind(const v1::TrackResponse& response) {
  switch (response.kind_case()) {
    case v1::TrackResponse::kOpened:
      return "opened";
    case v1::TrackResponse::kEstimate:
      return "estimate";
    case v1::TrackResponse::kRejected:
      return "rejected";
    case v1::TrackResponse::kGap:
      return "gap";
    case v1::TrackResponse::kTracks:
      return "tracks";
    case v1::TrackResponse::KIND_NOT_SET:
      break;
  }
  return "an empty response";
}

}  // namespace

TrackStream::TrackStream(std::shared_ptr<grpc::Channel> channel, std::string session_key)
    : channel_(std::move(channel)),
      stub_(v1::Localizer::NewStub(channel_)),
      session_key_(session_key.empty() ? RandomSessionKey() : std::move(session_key)) {
  SetSessionKey(&context_, session_key_);
  stream_ = stub_->Track(&context_);
}

TrackStream::~TrackStream() {
  if (!finished_) Abandon();
}

StatusOr<std::unique_ptr<TrackStream>> TrackStream::Open(std::shared_ptr<grpc::Channel> channel,
                                                         const v1::SessionConfig& config,
                                                         const std::string& session_key) {
  std::unique_ptr<TrackStream> stream(new TrackStream(std::move(channel), session_key));
  v1::TrackRequest request;
  *request.mutable_open() = config;
  LOCALIZER_RETURN_IF_ERROR(stream->Start(request));
  return stream;
}

StatusOr<std::unique_ptr<TrackStream>> TrackStream::Resume(std::shared_ptr<grpc::Channel> channel,
                                                           const std::string& session_id,
                                                           const std::string& resume_token,
                                                           std::optional<uint64_t> last_frame_received,
                                                           const std::string& session_key) {
  std::unique_ptr<TrackStream> stream(new TrackStream(std::move(channel), session_key));
  v1::TrackRequest request;
  v1::ResumeSession* resume = request.mutable_resume();
  resume->set_session_id(session_id);
  resume->set_resume_token(resume_token);
  if (last_frame_received) {
    resume->set_last_frame_received(*last_frame_received);
  } else {
    resume->set_received_none(true);  // 0 would mean "frame 0 received"
  }
  LOCALIZER_RETURN_IF_ERROR(stream->Start(request));
  return stream;
}

Status TrackStream::Start(const v1::TrackRequest& first) {
  // A failed Write means the call is already over; Read then fails too and Finish says why.
  v1::TrackResponse response;
  const bool written = stream_->Write(first);
  if (written && stream_->Read(&response)) {
    if (response.has_opened()) {
      opened_ = std::move(*response.mutable_opened());
      return Status::Ok();
    }
    const std::string kind = ResponseKind(response);
    Abandon();
    return Internal(std::string("INTERNAL: the server answered ") + (first.has_open() ? "open" : "resume") + " with " +
                    kind + " instead of opened");
  }
  const grpc::Status status = Finish();
  if (status.ok()) {
    return Internal("INTERNAL: the server ended the stream OK without answering " +
                    std::string(first.has_open() ? "open" : "resume"));
  }
  return wire::FromGrpcStatus(status);
}

bool TrackStream::Write(const v1::SampleBlock& block) {
  v1::TrackRequest request;
  // The block is copied once into the request; the caller's block stays untouched.
  *request.mutable_block() = block;
  return stream_->Write(request);
}

bool TrackStream::WriteImu(const v1::ImuBatch& batch) {
  v1::TrackRequest request;
  *request.mutable_imu() = batch;
  return stream_->Write(request);
}

bool TrackStream::WriteScan(const v1::Scan& scan) {
  v1::TrackRequest request;
  *request.mutable_scan() = scan;
  return stream_->Write(request);
}

bool TrackStream::Read(v1::TrackResponse* response) { return stream_->Read(response); }

void TrackStream::WritesDone() { stream_->WritesDone(); }

grpc::Status TrackStream::Finish() {
  finished_ = true;
  return FromProxyReset(stream_->Finish());
}

void TrackStream::Cancel() { context_.TryCancel(); }

grpc::Status TrackStream::Abandon() {
  context_.TryCancel();
  v1::TrackResponse ignored;
  while (stream_->Read(&ignored)) {
  }
  return Finish();
}

}  // namespace localizer::client
