#include "server/service/localizer_service.h"

#include "engine/pipeline/locate.h"
#include "engine/pipeline/session_memory.h"
#include "server/service/log.h"
#include "server/service/track_reactor.h"
#include "wire/locate_wire.h"
#include "wire/status_wire.h"
#include "wire/tsan_annotations.h"

namespace localizer::server {

namespace {

// A Track stream refused before it started (authentication): ends at once with `status`.
class RefusedStream final : public grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer> {
 public:
  explicit RefusedStream(const grpc::Status& status) {
    Finish(status);
    // gRPC (not built with TSan) orders Finish before OnDone; TSan learns it here
    // (tsan_annotations.h). After Finish: in the constructor gRPC only notes the status and
    // finishes once the reactor is bound, after this returns.
    wire::TsanRelease(this);
  }
  void OnDone() override {
    wire::TsanAcquire(this);
    delete this;
  }
};

}  // namespace

LocalizerService::LocalizerService(SessionRegistry* registry, WorkerPool* pool, ServiceMetrics* metrics,
                                   wire::ConfigPolicy policy, const TokenAuthenticator* auth,
                                   LocateLimits locate_limits)
    : registry_(registry),
      pool_(pool),
      metrics_(metrics),
      policy_(std::move(policy)),
      auth_(auth),
      locate_limits_(locate_limits) {}

grpc::Status LocalizerService::Authorize(grpc::CallbackServerContext* context, Role role, const char* method) const {
  if (auth_ == nullptr) return grpc::Status::OK;
  std::string_view authorization;
  const auto& metadata = context->client_metadata();
  if (const auto it = metadata.find(kAuthorizationMetadata); it != metadata.end()) {
    authorization = std::string_view(it->second.data(), it->second.size());
  }
  const AuthDecision decision = auth_->Check(authorization, role);
  if (decision == AuthDecision::kAllowed) return grpc::Status::OK;
  grpc::Status status = ToGrpcStatus(decision, method);
  const char* reason = RefusalReason(decision, authorization);
  if (metrics_ != nullptr) {
    if (auto* c = metrics_->auth_refusals(reason)) c->Increment();
  }
  LogEvent("warn", "auth_refused",
           {{"method", method},
            {"peer", context->peer()},
            {"code", decision == AuthDecision::kUnauthenticated ? "UNAUTHENTICATED" : "PERMISSION_DENIED"},
            {"reason", reason}});
  return status;
}

grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>* LocalizerService::Track(
    grpc::CallbackServerContext* context) {
  if (grpc::Status refused = Authorize(context, Role::kClient, "Track"); !refused.ok()) {
    return new RefusedStream(refused);
  }
  return new TrackReactor(context, registry_, metrics_);
}

Status LocateOnce(const v1::LocateRequest& request, const wire::ConfigPolicy& policy, v1::LocateResponse* response,
                  MemoryBudget* budget) {
  wire::DecodedLocate decoded;
  LOCALIZER_RETURN_IF_ERROR(wire::DecodeLocateRequest(request, policy, &decoded));
  MemoryBudget::Charge charge;  // held until the transforms are done
  if (budget != nullptr) {
    auto charged = budget->Reserve(engine::LocateMemoryBytes(decoded.config, decoded.block.view.samples_per_channel),
                                   "a Locate of this block");
    if (!charged.ok()) return charged.status();
    charge = std::move(charged).value();
  }
  auto result = engine::Locate(decoded.config, decoded.block.view);
  if (!result.ok()) return result.status();
  const auto array = engine::ArrayGeometry::Create(decoded.config.sensors_m, decoded.config.sound_speed_mps,
                                                   decoded.config.reference_sensor);
  if (!array.ok()) return array.status();  // Locate accepted the same geometry: never here
  wire::LocateResultToProto(*result, *array, response);
  return Status::Ok();
}

grpc::ServerUnaryReactor* LocalizerService::Locate(grpc::CallbackServerContext* context,
                                                   const grpc::ByteBuffer* request, grpc::ByteBuffer* response) {
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  if (grpc::Status refused = Authorize(context, Role::kClient, "Locate"); !refused.ok()) {
    reactor->Finish(refused);
    return reactor;
  }
  auto answer = [this, reactor](const Status& status) {
    if (auto* c = metrics_->locate_requests(StatusCodeName(status.code()))) c->Increment();
    reactor->Finish(wire::ToGrpcStatus(status));
  };
  if (draining_) {
    answer(Unavailable("server is draining"));
    return reactor;
  }
  if (locate_in_flight_.fetch_add(1) >= locate_limits_.max_concurrent) {
    locate_in_flight_.fetch_sub(1);
    answer(ResourceExhausted(std::to_string(locate_limits_.max_concurrent) +
                             " Locate calls are in flight, this server's limit (--max-concurrent-locate)"));
    return reactor;
  }
  auto finish = [this, answer](const Status& status) {
    locate_in_flight_.fetch_sub(1);
    answer(status);
  };
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
    const Status status = LocateOnce(parsed, policy_, &typed, locate_limits_.budget);
    if (status.ok()) {
      bool own_buffer = false;
      const grpc::Status serialized =
          grpc::SerializationTraits<v1::LocateResponse>::Serialize(typed, response, &own_buffer);
      if (!serialized.ok())
        return finish(Internal("could not serialize the LocateResponse: " + serialized.error_message()));
    }
    finish(status);
  });
  if (!queued) finish(Unavailable("server is shutting down"));
  return reactor;
}

grpc::ServerUnaryReactor* LocalizerService::ListSessions(grpc::CallbackServerContext* context,
                                                         const v1::ListSessionsRequest* /*request*/,
                                                         v1::ListSessionsResponse* response) {
  if (grpc::Status refused = Authorize(context, Role::kOperator, "ListSessions"); !refused.ok()) {
    grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
    reactor->Finish(refused);
    return reactor;
  }
  for (v1::SessionInfo& info : registry_->List()) *response->add_sessions() = std::move(info);
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  reactor->Finish(grpc::Status::OK);
  return reactor;
}

grpc::ServerUnaryReactor* LocalizerService::CloseSession(grpc::CallbackServerContext* context,
                                                         const v1::CloseSessionRequest* request,
                                                         v1::CloseSessionResponse* response) {
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  if (grpc::Status refused = Authorize(context, Role::kOperator, "CloseSession"); !refused.ok()) {
    reactor->Finish(refused);
    return reactor;
  }
  auto frames = registry_->Close(request->session_id(), request->resume_token());
  if (frames.ok()) response->set_frames_processed(*frames);
  reactor->Finish(wire::ToGrpcStatus(frames.status()));
  return reactor;
}

}  // namespace localizer::server
