// A running localizer server: the gRPC service (with the standard health and reflection
// services), the worker pool, the session registry, and the HTTP endpoint (/metrics, the
// live view at /, /sessions), with TLS / mutual TLS and bearer tokens when the options name
// their files (tls_credentials.h, auth.h; docs/SECURITY.md). With metrics_tls_cert the HTTP
// side is HTTPS: civetweb listens on an ephemeral loopback port and a TlsFront
// (server/metrics/tls_front.h) on metrics_listen; metrics_port() is the front's.
//
//   auto server = Server::Start(options);   // listening when this returns
//   ... server->grpc_port(), server->metrics_port()
//   server->Shutdown();                     // graceful: see below
//
// Shutdown, in order: health turns NOT_SERVING; new sessions, resumes and Locates get
// UNAVAILABLE; every attached stream stops reading, and finishes with UNAVAILABLE once the
// blocks it had accepted are processed and their estimates written (at most
// drain_timeout_s); then gRPC shuts down (cancelling what is left), the workers stop and
// /metrics closes. Thread-safe; Shutdown is idempotent and also run by the destructor.
#pragma once

#include <grpcpp/grpcpp.h>

#include <memory>

#include "server/metrics/http_exposer.h"
#include "server/metrics/registry.h"
#include "server/metrics/tls_front.h"
#include "server/service/auth.h"
#include "server/service/finished_sessions.h"
#include "server/service/localizer_service.h"
#include "server/service/memory_budget.h"
#include "server/service/server_options.h"
#include "server/service/service_metrics.h"
#include "server/service/session_registry.h"
#include "server/service/worker_pool.h"
#include "server/sync/mutex.h"

namespace localizer::server {

class Server final {
 public:
  // INVALID_ARGUMENT for bad options (including TLS or token files that cannot be read or
  // parsed, naming the flag and path); UNAVAILABLE when an address cannot be bound.
  static StatusOr<std::unique_ptr<Server>> Start(const ServerOptions& options);
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  int grpc_port() const { return grpc_port_; }
  int metrics_port() const { return metrics_port_; }  // 0: no HTTP endpoint; HTTPS: the public port
  void Shutdown() EXCLUDES(shutdown_mutex_);

 private:
  explicit Server(const ServerOptions& options);

  const ServerOptions options_;
  metrics::Registry registry_;
  std::unique_ptr<ServiceMetrics> metrics_;
  std::unique_ptr<MemoryBudget> budget_;        // outlives the sessions and calls charged to it
  std::unique_ptr<FinishedSessions> finished_;  // the live view's ended sessions; outlives the registry
  std::unique_ptr<WorkerPool> pool_;
  std::unique_ptr<SessionRegistry> sessions_;
  std::unique_ptr<TokenAuthenticator> auth_;  // null: no authentication
  std::unique_ptr<LocalizerService> service_;
  std::unique_ptr<grpc::Server> grpc_;
  std::unique_ptr<metrics::HttpExposer> exposer_;
  // With --metrics-tls-cert: HTTPS on metrics_listen, relaying to exposer_ on loopback;
  // stopped before exposer_.
  std::unique_ptr<metrics::TlsFront> tls_front_;
  int grpc_port_ = 0;
  // Set once by Start, read by metrics_port() from any thread (exposer_ itself is reset by
  // Shutdown, which may run concurrently).
  int metrics_port_ = 0;
  Mutex shutdown_mutex_;
  bool shut_down_ GUARDED_BY(shutdown_mutex_) = false;
};

}  // namespace localizer::server
