// The localizer.v1.Localizer service (callback API): Track streams are TrackReactors;
// Locate runs on the worker pool; ListSessions and CloseSession answer from the registry.
// Thread-safe; the registry, pool and metrics must outlive it.
#pragma once

#include <atomic>

#include "localizer/v1/localizer.grpc.pb.h"
#include "server/service/auth.h"
#include "server/service/memory_budget.h"
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

// Bounds on Locate: calls queued or running at once (more are RESOURCE_EXHAUSTED at once,
// before their request is parsed), and the memory budget each call is charged to while it
// runs (engine/pipeline/session_memory.h LocateMemoryBytes; null: not charged).
struct LocateLimits {
  int max_concurrent = 16;
  MemoryBudget* budget = nullptr;
};

class LocalizerService final : public LocalizerCallbackBase {
 public:
  // `auth` null: every call is allowed; else each call is checked first (auth.h: Track and
  // Locate need a client or operator token, ListSessions and CloseSession an operator token)
  // and a refused one ends with UNAUTHENTICATED or PERMISSION_DENIED before anything else
  // runs. `auth` must outlive the service.
  LocalizerService(SessionRegistry* registry, WorkerPool* pool, ServiceMetrics* metrics, wire::ConfigPolicy policy,
                   const TokenAuthenticator* auth = nullptr, LocateLimits locate_limits = {});

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
  // OK when `context`'s authorization metadata allows a call needing `role` (always without
  // auth_); else the refusal, logged with the method, peer and reason and counted in
  // localizer_auth_refusals_total{reason}.
  grpc::Status Authorize(grpc::CallbackServerContext* context, Role role, const char* method) const;

  const TokenAuthenticator* const auth_;
  const LocateLimits locate_limits_;
  std::atomic<int> locate_in_flight_{0};
  std::atomic<bool> draining_{false};
};

// The body of Locate (exposed for tests): decode, charge `budget` (when given) for the
// transforms, GCC-PHAT, multilaterate.
Status LocateOnce(const v1::LocateRequest& request, const wire::ConfigPolicy& policy, v1::LocateResponse* response,
                  MemoryBudget* budget = nullptr);

}  // namespace localizer::server
