#include "server/service/server.h"

#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/health_check_service_interface.h>

#include <thread>

#include "engine/pipeline/backend.h"
#include "gpu/backend/gpu_backend.h"
#include "server/service/auth.h"
#include "server/service/live_page.h"
#include "server/service/log.h"
#include "server/service/refusal_log.h"
#include "server/service/sessions_json.h"
#include "server/service/tls_credentials.h"
#include "server/service/transport_limits.h"
#include "server/service/version.h"

namespace localizer::server {
namespace {

// localizer_gpu_batches_total{stage} and localizer_gpu_batched_total{stage}, read from the
// GPU dispatchers at each scrape (zero without GPU sessions).
Status AddGpuBatchMetrics(metrics::Registry* registry) {
  auto batches = registry->AddCounter("localizer_gpu_batches_total",
                                      "GPU launch sequences run, by stage (gcc, filter).", {"stage"});
  if (!batches.ok()) return batches.status();
  auto batched =
      registry->AddCounter("localizer_gpu_batched_total",
                           "Frames (stage gcc) or filter steps (stage filter) run in GPU batches; divided by "
                           "localizer_gpu_batches_total it is the mean batch size.",
                           {"stage"});
  if (!batched.ok()) return batched.status();
  std::vector<metrics::Counter*> series;
  for (auto* family : {*batches, *batched}) {
    for (const char* stage : {"gcc", "filter"}) {
      auto one = family->WithLabels({stage});
      if (!one.ok()) return one.status();
      series.push_back(*one);
    }
  }
  registry->AddCollector([series] {
    const gpu::GpuBatchCounts c = gpu::BatchCounts();
    const double now[] = {static_cast<double>(c.gcc_batches), static_cast<double>(c.filter_batches),
                          static_cast<double>(c.gcc_frames), static_cast<double>(c.filter_steps)};
    for (size_t i = 0; i < series.size(); ++i) series[i]->Increment(now[i] - series[i]->value());
  });
  return Status::Ok();
}

// An HTTP guard's answer for a decision: 0 (serve), 401 or 403.
int HttpRefusal(AuthDecision decision) {
  switch (decision) {
    case AuthDecision::kAllowed:
      return 0;
    case AuthDecision::kUnauthenticated:
      return 401;
    case AuthDecision::kPermissionDenied:
      return 403;
  }
  return 403;
}

// An operator page's guard: 0 to serve, else 401 or 403, counting the refusal in
// localizer_auth_refusals_total{reason} as the gRPC check does, and logging it (rate-limited).
int OperatorPageGuard(const TokenAuthenticator& auth, ServiceMetrics* metrics, HttpRefusalLog* log,
                      const std::string& page, const std::string& authorization) {
  const AuthDecision decision = auth.Check(authorization, Role::kOperator);
  if (decision == AuthDecision::kAllowed) return 0;
  const char* reason = RefusalReason(decision, authorization);
  if (auto* c = metrics->auth_refusals(reason)) c->Increment();
  const int code = HttpRefusal(decision);
  log->Note(HttpRefusalLog::Clock::now(), page, code, reason);
  return code;
}

// The HTTPS front of the HTTP side: its handshake failures counted in
// localizer_http_tls_handshake_failures_total{reason} and logged at most once a minute
// (event=http_tls_handshake_failures, with how many since the last line), so that a flood of
// bad connections cannot flood the log.
StatusOr<std::unique_ptr<metrics::TlsFront>> StartTlsFront(const std::string& listen, int backend_port, TlsPem pem,
                                                           ServiceMetrics* m) {
  metrics::TlsFrontOptions front;
  front.cert_chain_pem = std::move(pem.cert);
  front.key_pem = std::move(pem.key);
  front.client_ca_pem = std::move(pem.client_ca);
  front.handshake_failures = m->http_tls_handshake_failures;
  front.report_interval_s = 60.0;
  front.report_failures = [interval_s = front.report_interval_s](const metrics::HandshakeFailureReport& report) {
    LogEvent("warn", "http_tls_handshake_failures",
             {{"failures", std::to_string(report.failures)},
              {"interval_s", std::to_string(static_cast<int>(interval_s))},
              {"last_reason", report.last_reason},
              {"last_detail", report.last_detail},
              {"last_peer", report.last_peer}});
  };
  return metrics::TlsFront::Start(listen, backend_port, std::move(front));
}

}  // namespace

Server::Server(const ServerOptions& options) : options_(options) {}

StatusOr<std::unique_ptr<Server>> Server::Start(const ServerOptions& options) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  SetLogLevel(options.log_level);
  // The files first: a bad one stops the start before anything runs.
  auto credentials = MakeServerCredentials(options);
  if (!credentials.ok()) return credentials.status();
  TlsPem metrics_tls;
  if (!options.metrics_tls_cert.empty()) {
    auto pem =
        ReadTlsFiles("--metrics-tls", options.metrics_tls_cert, options.metrics_tls_key, options.metrics_tls_client_ca);
    if (!pem.ok()) return pem.status();
    metrics_tls = std::move(pem).value();
  }
  std::unique_ptr<TokenAuthenticator> auth;
  if (!options.auth_token_file.empty()) {
    auto loaded = TokenAuthenticator::Load(options.auth_token_file);
    if (!loaded.ok()) return loaded.status();
    auth = std::move(loaded).value();
  }
  std::unique_ptr<Server> s(new Server(options));
  s->auth_ = std::move(auth);
  auto metrics = ServiceMetrics::Create(&s->registry_, options.backend);
  if (!metrics.ok()) return metrics.status();
  s->metrics_ = std::move(metrics).value();
  gpu::GpuBackendOptions gpu_options;
  gpu_options.batch_window_s = options.gpu_batch_window_ms * 1e-3;
  gpu_options.max_batch_frames = options.gpu_max_batch;
  gpu_options.bank_limit_bytes = static_cast<std::size_t>(options.gpu_bank_mib) << 20;
  LOCALIZER_RETURN_IF_ERROR(gpu::RegisterGpuBackend(gpu_options));
  const std::string gpu_reason = engine::GpuUnavailableReason();
  const bool gpu_sessions = gpu_reason.empty() && options.backend != "cpu";
  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  // GPU sessions block their worker while their frame waits in a batch: one worker per
  // session keeps every session's frame in the next batch.
  const int workers = options.workers > 0 ? options.workers
                      : gpu_sessions      ? std::max(cores, std::min(1024, options.max_sessions))
                                          : cores;
  s->pool_ = std::make_unique<WorkerPool>(workers);
  s->budget_ = std::make_unique<MemoryBudget>(options.memory_budget_mib > 0
                                                  ? static_cast<int64_t>(options.memory_budget_mib) << 20
                                                  : DefaultMemoryBudgetBytes());

  RegistryOptions registry_options;
  registry_options.max_sessions = options.max_sessions;
  registry_options.ttl_s = options.session_ttl_s;
  registry_options.idle_s = options.session_idle_timeout_s;
  registry_options.memory_trim_s = options.memory_trim_s;
  registry_options.host.max_queued_requests = options.max_queued_requests;
  registry_options.host.ttl_s = options.session_ttl_s;
  registry_options.policy.default_backend = options.backend;
  registry_options.policy.max_block_samples = options.max_block_samples;
  registry_options.policy.max_channels = options.max_channels;
  registry_options.policy.max_particles = options.max_particles;
  registry_options.policy.max_tracks = options.max_tracks;
  registry_options.policy.max_plots_per_scan = options.max_scan_plots;
  // The live view keeps the sessions that ended (only when it is served).
  s->finished_ = std::make_unique<FinishedSessions>(options.metrics_listen.empty() ? 0 : options.live_keep_finished,
                                                    options.live_keep_finished_s);
  if (s->finished_->enabled()) {
    FinishedSessions* finished = s->finished_.get();
    registry_options.on_retired = [finished](const SessionHost& host, const v1::SessionInfo& info,
                                             const std::string& reason) {
      finished->Add({FinishedSessionJson(host, info), reason, Clock::now()});
    };
  }
  s->sessions_ =
      std::make_unique<SessionRegistry>(registry_options, s->pool_.get(), s->metrics_.get(), s->budget_.get());
  LocateLimits locate_limits{options.max_concurrent_locate > 0 ? options.max_concurrent_locate : workers,
                             s->budget_.get()};
  s->service_ = std::make_unique<LocalizerService>(s->sessions_.get(), s->pool_.get(), s->metrics_.get(),
                                                   registry_options.policy, s->auth_.get(), locate_limits);
  SessionRegistry* sessions = s->sessions_.get();
  ServiceMetrics* m = s->metrics_.get();
  MemoryBudget* budget = s->budget_.get();
  s->registry_.AddCollector([budget, m] {
    m->budget_used->Set(static_cast<double>(budget->used_bytes()));
    m->budget_limit->Set(static_cast<double>(budget->budget_bytes()));
  });
  s->registry_.AddCollector([sessions, m] {
    size_t attached = 0, total = 0;
    for (const auto& host : sessions->Snapshot()) {
      ++total;
      attached += host->attached() ? 1 : 0;
    }
    m->attached->Set(static_cast<double>(attached));
    m->detached->Set(static_cast<double>(total - attached));
  });

  LOCALIZER_RETURN_IF_ERROR(AddGpuBatchMetrics(&s->registry_));
  if (options.backend == "gpu" && !gpu_reason.empty()) {
    LogEvent("warn", "gpu_unavailable", {{"reason", gpu_reason}});
  }

  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  grpc::ServerBuilder builder;
  builder.AddListeningPort(options.listen, *credentials, &s->grpc_port_);
  builder.SetMaxReceiveMessageSize(options.max_message_bytes);
  builder.SetMaxSendMessageSize(options.max_message_bytes);
  ApplyTransportLimits(options.transport, &builder);
  builder.RegisterService(s->service_.get());
  s->grpc_ = builder.BuildAndStart();
  if (!s->grpc_ || s->grpc_port_ == 0) {
    return Unavailable("cannot listen for gRPC on " + options.listen + " (address in use or not local?)");
  }
  if (!options.metrics_listen.empty()) {
    const bool https = !options.metrics_tls_cert.empty();
    // With HTTPS, civetweb serves plaintext on loopback only, behind the TLS front.
    auto exposer = metrics::HttpExposer::Start(https ? "127.0.0.1:0" : options.metrics_listen, &s->registry_);
    if (!exposer.ok()) {
      s->grpc_->Shutdown();
      return exposer.status();
    }
    s->exposer_ = std::move(exposer).value();
    if (https) {
      auto front = StartTlsFront(options.metrics_listen, s->exposer_->port(), std::move(metrics_tls), m);
      if (!front.ok()) {
        s->grpc_->Shutdown();
        return front.status();
      }
      s->tls_front_ = std::move(front).value();
    }
    // The public port: the front's with HTTPS (civetweb's loopback port is not announced).
    s->metrics_port_ = s->tls_front_ ? s->tls_front_->port() : s->exposer_->port();
    // The live view: GET / draws what GET /sessions lists. The exposer is stopped before
    // the registry is destroyed (Shutdown), so `sessions` outlives every request.
    const double ttl_s = options.session_ttl_s;
    FinishedSessions* finished = s->finished_.get();
    auto sessions_page = [sessions, finished, ttl_s] {
      const Clock::time_point now = Clock::now();
      return std::pair<int, std::string>(200, SessionsJson(sessions->Snapshot(), now, ttl_s, finished->Snapshot(now)));
    };
    auto live_page = [] { return std::pair<int, std::string>(200, std::string(LivePageHtml())); };
    // With tokens, both need an operator token: /sessions in the Authorization header (the
    // page's script sends it), / also as ?token= (a browser cannot set a header when it
    // navigates). /metrics stays open: it holds aggregate counters, no session identity.
    metrics::HttpExposer::PageGuard sessions_guard, page_guard;
    if (const TokenAuthenticator* tokens = s->auth_.get()) {
      auto refusals = std::make_shared<HttpRefusalLog>();  // one rate limit for both pages
      sessions_guard = [tokens, m, refusals](const metrics::HttpExposer::Credentials& c) {
        return OperatorPageGuard(*tokens, m, refusals.get(), "/sessions", c.authorization);
      };
      page_guard = [tokens, m, refusals](const metrics::HttpExposer::Credentials& c) {
        const std::string authorization =
            c.authorization.empty() && !c.query_token.empty() ? "Bearer " + c.query_token : c.authorization;
        return OperatorPageGuard(*tokens, m, refusals.get(), "/", authorization);
      };
    }
    LOCALIZER_RETURN_IF_ERROR(s->exposer_->AddPage("/sessions", std::move(sessions_page),
                                                   "application/json; charset=utf-8", std::move(sessions_guard)));
    LOCALIZER_RETURN_IF_ERROR(
        s->exposer_->AddPage("/", std::move(live_page), "text/html; charset=utf-8", std::move(page_guard)));
  }
  if (s->auth_ && options.tls_cert.empty()) {
    LogEvent("warn", "auth_without_tls",
             {{"detail", "bearer tokens travel in plaintext; use --tls-cert/--tls-key or a TLS proxy"}});
  }
  const std::string& http = options.metrics_listen;
  const bool http_loopback =
      http.rfind("127.", 0) == 0 || http.rfind("localhost:", 0) == 0 || http.rfind("[::1]:", 0) == 0;
  if (s->auth_ && !http.empty() && !http_loopback && options.metrics_tls_cert.empty()) {
    LogEvent("warn", "auth_without_https",
             {{"detail",
               "operator tokens for /sessions and / travel in plaintext HTTP; use "
               "--metrics-tls-cert/--metrics-tls-key"}});
  }
  grpc::HealthCheckServiceInterface* health = s->grpc_->GetHealthCheckService();
  if (health != nullptr) {
    health->SetServingStatus(true);
    health->SetServingStatus("localizer.v1.Localizer", true);
  }
  LogEvent("info", "server_start",
           {{"version", kLocalizerVersion},
            {"grpc_port", std::to_string(s->grpc_port_)},
            {"metrics_port", std::to_string(s->metrics_port())},
            {"workers", std::to_string(workers)},
            {"backend", options.backend},
            {"tls", options.tls_cert.empty()        ? "off"
                    : options.tls_client_ca.empty() ? "on"
                                                    : "mutual"},
            {"metrics_tls", options.metrics_listen.empty() || options.metrics_tls_cert.empty() ? "off"
                            : options.metrics_tls_client_ca.empty()                            ? "on"
                                                                                               : "mutual"},
            {"auth", s->auth_ ? std::to_string(s->auth_->token_count()) + " tokens" : "off"},
            {"max_sessions", std::to_string(options.max_sessions)},
            {"gpu", gpu_reason.empty() ? gpu::DeviceName() : "none: " + gpu_reason}});
  return s;
}

Server::~Server() { Shutdown(); }

void Server::Shutdown() {
  MutexLock lock(&shutdown_mutex_);
  if (shut_down_) return;
  shut_down_ = true;
  if (!grpc_ || !sessions_ || !service_ || !pool_) {
    // Start failed part-way: stop what was started, in the same order.
    if (grpc_) grpc_->Shutdown();
    tls_front_.reset();
    exposer_.reset();
    sessions_.reset();
    if (pool_) pool_->Shutdown();
    return;
  }
  const auto start = Clock::now();
  if (grpc::HealthCheckServiceInterface* health = grpc_->GetHealthCheckService()) {
    health->SetServingStatus(false);
    health->SetServingStatus("localizer.v1.Localizer", false);
  }
  sessions_->StartDrain();
  service_->StartDrain();
  const auto hosts = sessions_->Snapshot();
  LogEvent("info", "drain_start", {{"sessions", std::to_string(hosts.size())}});
  for (const auto& host : hosts) host->Drain();
  const auto deadline =
      start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(options_.drain_timeout_s));
  for (;;) {
    bool drained = true;
    for (const auto& host : hosts) drained &= host->Drained();
    if (drained || Clock::now() >= deadline) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  // Streams still open get cancelled after a short grace for their final writes.
  grpc_->Shutdown(std::chrono::system_clock::now() + std::chrono::milliseconds(500));
  // The HTTP server goes first: its collectors and /sessions read the session registry
  // (its destructor waits for requests in flight). The TLS front relays to it: it goes before.
  tls_front_.reset();
  exposer_.reset();
  sessions_.reset();  // closes what is left
  pool_->Shutdown();
  LogEvent("info", "server_stop",
           {{"drain_s", std::to_string(std::chrono::duration<double>(Clock::now() - start).count())}});
}

}  // namespace localizer::server
