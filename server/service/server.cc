#include "server/service/server.h"

#include <thread>

#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/health_check_service_interface.h>

#include "server/service/log.h"
#include "server/service/version.h"

namespace localizer::server {

Server::Server(const ServerOptions& options) : options_(options) {}

StatusOr<std::unique_ptr<Server>> Server::Start(const ServerOptions& options) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  SetLogLevel(options.log_level);
  std::unique_ptr<Server> s(new Server(options));
  auto metrics = ServiceMetrics::Create(&s->registry_, options.backend);
  if (!metrics.ok()) return metrics.status();
  s->metrics_ = std::move(metrics).value();
  const int workers =
      options.workers > 0 ? options.workers : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  s->pool_ = std::make_unique<WorkerPool>(workers);

  RegistryOptions registry_options;
  registry_options.max_sessions = options.max_sessions;
  registry_options.ttl_s = options.session_ttl_s;
  registry_options.host.max_queue_blocks = options.max_queue_blocks;
  registry_options.host.ttl_s = options.session_ttl_s;
  registry_options.policy.default_backend = options.backend;
  registry_options.policy.max_block_samples = options.max_block_samples;
  registry_options.policy.max_channels = options.max_channels;
  registry_options.policy.max_particles = options.max_particles;
  s->sessions_ = std::make_unique<SessionRegistry>(registry_options, s->pool_.get(), s->metrics_.get());
  s->service_ = std::make_unique<LocalizerService>(s->sessions_.get(), s->pool_.get(), s->metrics_.get(),
                                                   registry_options.policy);
  SessionRegistry* sessions = s->sessions_.get();
  ServiceMetrics* m = s->metrics_.get();
  s->registry_.AddCollector([sessions, m] {
    size_t attached = 0, total = 0;
    for (const auto& host : sessions->Snapshot()) {
      ++total;
      attached += host->attached() ? 1 : 0;
    }
    m->attached->Set(static_cast<double>(attached));
    m->detached->Set(static_cast<double>(total - attached));
  });

  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  grpc::ServerBuilder builder;
  builder.AddListeningPort(options.listen, grpc::InsecureServerCredentials(), &s->grpc_port_);
  builder.SetMaxReceiveMessageSize(options.max_message_bytes);
  builder.SetMaxSendMessageSize(options.max_message_bytes);
  builder.RegisterService(s->service_.get());
  s->grpc_ = builder.BuildAndStart();
  if (!s->grpc_ || s->grpc_port_ == 0) {
    return Unavailable("cannot listen for gRPC on " + options.listen + " (address in use or not local?)");
  }
  if (!options.metrics_listen.empty()) {
    auto exposer = metrics::HttpExposer::Start(options.metrics_listen, &s->registry_);
    if (!exposer.ok()) {
      s->grpc_->Shutdown();
      return exposer.status();
    }
    s->exposer_ = std::move(exposer).value();
  }
  grpc::HealthCheckServiceInterface* health = s->grpc_->GetHealthCheckService();
  if (health != nullptr) {
    health->SetServingStatus(true);
    health->SetServingStatus("localizer.v1.Localizer", true);
  }
  LogEvent("info", "server_start",
           {{"version", kLocalizerVersion}, {"grpc_port", std::to_string(s->grpc_port_)},
            {"metrics_port", std::to_string(s->metrics_port())}, {"workers", std::to_string(workers)},
            {"backend", options.backend}, {"max_sessions", std::to_string(options.max_sessions)}});
  return s;
}

Server::~Server() { Shutdown(); }

void Server::Shutdown() {
  std::lock_guard<std::mutex> lock(shutdown_mutex_);
  if (shut_down_) return;
  shut_down_ = true;
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
  const auto deadline = start + std::chrono::duration_cast<Clock::duration>(
                                    std::chrono::duration<double>(options_.drain_timeout_s));
  for (;;) {
    bool drained = true;
    for (const auto& host : hosts) drained &= host->Drained();
    if (drained || Clock::now() >= deadline) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  // Streams still open get cancelled after a short grace for their final writes.
  grpc_->Shutdown(std::chrono::system_clock::now() + std::chrono::milliseconds(500));
  sessions_.reset();  // closes what is left
  pool_->Shutdown();
  exposer_.reset();
  LogEvent("info", "server_stop",
           {{"drain_s", std::to_string(std::chrono::duration<double>(Clock::now() - start).count())}});
}

}  // namespace localizer::server
