// The localizer.v1.Localizer service (callback API): Track streams are TrackReactors;
// Locate runs on the worker pool; ListSessions and CloseSession answer from the registry.
// Thread-safe; the registry, pool and metrics must outlive it.
#pragma once

#include <atomic>

#include "localizer/v1/localizer.grpc.pb.h"
#include "server/service/service_metrics.h"
#include "server/service/session_registry.h"
#include "server/service/worker_pool.h"
#include "wire/config_wire.h"

namespace localizer::server {

// Track is registered raw (ByteBuffer) so its reactor can tell a request that does not
// parse from the client's half-close (see track_reactor.h); Locate is raw so that an
// unparseable request is INVALID_ARGUMENT with a message (gRPC's typed unary handler answers
// UNIMPLEMENTED with none before our code runs); the rest are typed.
using LocalizerCallbackBase = v1::Localizer::WithRawCallbackMethod_Track<
    v1::Localizer::WithRawCallbackMethod_Locate<v1::Localizer::WithCallbackMethod_ListSessions<
        v1::Localizer::WithCallbackMethod_CloseSession<v1::Localizer::Service>>>>;

class LocalizerService final : public LocalizerCallbackBase {
 public:
  LocalizerService(SessionRegistry* registry, WorkerPool* pool, ServiceMetrics* metrics, wire::ConfigPolicy policy);

  grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>* Track(grpc::CallbackServerContext* context) override;
  grpc::ServerUnaryReactor* Locate(grpc::CallbackServerContext* context, const grpc::ByteBuffer* request,
                                   grpc::ByteBuffer* response) override;
  grpc::ServerUnaryReactor* ListSessions(grpc::CallbackServerContext* context, const v1::ListSessionsRequest* request,
                                         v1::ListSessionsResponse* response) override;
  grpc::ServerUnaryReactor* CloseSession(grpc::CallbackServerContext* context, const v1::CloseSessionRequest* request,
                                         v1::CloseSessionResponse* response) override;

  // From now on Locate answers UNAVAILABLE (Track refusals come from the registry).
  void StartDrain() { draining_ = true; }

 private:
  SessionRegistry* const registry_;
  WorkerPool* const pool_;
  ServiceMetrics* const metrics_;
  const wire::ConfigPolicy policy_;
  std::atomic<bool> draining_{false};
};

// The body of Locate (exposed for tests): decode, GCC-PHAT, multilaterate.
Status LocateOnce(const v1::LocateRequest& request, const wire::ConfigPolicy& policy, v1::LocateResponse* response);

}  // namespace localizer::server
