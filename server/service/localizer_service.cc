#include "server/service/localizer_service.h"

#include "engine/pipeline/locate.h"
#include "server/service/track_reactor.h"
#include "server/wire/block_wire.h"
#include "server/wire/status_wire.h"

namespace localizer::server {

LocalizerService::LocalizerService(SessionRegistry* registry, WorkerPool* pool, ServiceMetrics* metrics,
                                   wire::ConfigPolicy policy)
    : registry_(registry), pool_(pool), metrics_(metrics), policy_(std::move(policy)) {}

grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>* LocalizerService::Track(
    grpc::CallbackServerContext* context) {
  return new TrackReactor(context, registry_, metrics_);
}

Status LocateOnce(const v1::LocateRequest& request, const wire::ConfigPolicy& policy, v1::LocateResponse* response) {
  if (request.config().has_detections()) {
    return InvalidArgument("config.detections: Locate measures one block of samples; detection configs open Track sessions");
  }
  auto config = wire::ConfigFromProto(request.config(), policy);
  if (!config.ok()) return config.status();
  wire::DecodedBlock decoded;
  std::string reason;
  LOCALIZER_RETURN_IF_ERROR(wire::DecodeBlock(
      request.block(), {static_cast<int>(config->sensors_m.size()), config->max_block_samples}, &decoded, &reason));
  auto result = engine::Locate(*config, decoded.view);
  if (!result.ok()) return result.status();
  const auto array = engine::ArrayGeometry::Create(config->sensors_m, config->sound_speed_mps, config->reference_sensor);
  for (size_t p = 0; p < result->measurement.pairs.size(); ++p) {
    const engine::PairMeasurement& m = result->measurement.pairs[p];
    v1::PairTdoa* pair = response->add_pairs();
    pair->set_sensor(static_cast<uint32_t>(array->sensor_of_pair(static_cast<int>(p))));
    pair->set_delay_s(m.delay_s);
    pair->set_quality(m.quality);
    pair->set_peak_snr(m.peak_snr);
  }
  response->set_fix_found(result->fix_found);
  if (result->fix_found) {
    response->mutable_position_m()->set_x(result->fix.position_m.x());
    response->mutable_position_m()->set_y(result->fix.position_m.y());
    response->mutable_position_m()->set_z(result->fix.position_m.z());
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) response->add_covariance(result->fix.covariance_m2(r, c));
    }
    response->set_residual_rms_s(result->fix.rms_residual_s);
  }
  response->set_tdoa_s(result->tdoa_s);
  return Status::Ok();
}

grpc::ServerUnaryReactor* LocalizerService::Locate(grpc::CallbackServerContext* context,
                                                   const grpc::ByteBuffer* request, grpc::ByteBuffer* response) {
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  auto finish = [this, reactor](const Status& status) {
    if (auto* c = metrics_->locate_requests(StatusCodeName(status.code()))) c->Increment();
    reactor->Finish(wire::ToGrpcStatus(status));
  };
  if (draining_) {
    finish(Unavailable("server is draining"));
    return reactor;
  }
  // The request's bytes stay valid until Finish; decoding (up to the message limit) runs on
  // the worker pool with the rest of the work.
  const bool queued = pool_->Submit([this, request, response, finish] {
    v1::LocateRequest parsed;
    grpc::ByteBuffer copy(*request);  // Deserialize consumes its buffer
    const size_t bytes = request->Length();
    if (!grpc::SerializationTraits<v1::LocateRequest>::Deserialize(&copy, &parsed).ok()) {
      finish(InvalidArgument("LocateRequest of " + std::to_string(bytes) +
                             " bytes could not be parsed (not a serialized localizer.v1.LocateRequest)"));
      return;
    }
    v1::LocateResponse typed;
    const Status status = LocateOnce(parsed, policy_, &typed);
    if (status.ok()) {
      bool own_buffer = false;
      const grpc::Status serialized = grpc::SerializationTraits<v1::LocateResponse>::Serialize(typed, response, &own_buffer);
      if (!serialized.ok()) return finish(Internal("could not serialize the LocateResponse: " + serialized.error_message()));
    }
    finish(status);
  });
  if (!queued) finish(Unavailable("server is shutting down"));
  return reactor;
}

grpc::ServerUnaryReactor* LocalizerService::ListSessions(grpc::CallbackServerContext* context,
                                                         const v1::ListSessionsRequest* /*request*/,
                                                         v1::ListSessionsResponse* response) {
  for (v1::SessionInfo& info : registry_->List()) *response->add_sessions() = std::move(info);
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  reactor->Finish(grpc::Status::OK);
  return reactor;
}

grpc::ServerUnaryReactor* LocalizerService::CloseSession(grpc::CallbackServerContext* context,
                                                         const v1::CloseSessionRequest* request,
                                                         v1::CloseSessionResponse* response) {
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  auto frames = registry_->Close(request->session_id(), request->resume_token());
  if (frames.ok()) response->set_frames_processed(*frames);
  reactor->Finish(wire::ToGrpcStatus(frames.status()));
  return reactor;
}

}  // namespace localizer::server
