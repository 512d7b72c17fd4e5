#include "server/service/session_registry.h"

#include <sstream>
#include <utility>

#include "wire/string_limits.h"

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "engine/pipeline/session_memory.h"
#include "server/service/log.h"
#include "server/service/secure_random.h"
#include "server/service/session_charge.h"

namespace localizer::server {
namespace {

std::string ShortSeconds(double s) {
  std::ostringstream out;
  out << s;
  return out.str();
}

// A session reference from a client (Resume, CloseSession) within its documented lengths.
Status CheckSessionRef(const std::string& id, const std::string& token) {
  LOCALIZER_RETURN_IF_ERROR(wire::CheckLength("session_id", id, wire::kMaxSessionIdBytes));
  return wire::CheckLength("resume_token", token, wire::kMaxResumeTokenBytes);
}

}  // namespace

SessionRegistry::SessionRegistry(RegistryOptions options, WorkerPool* pool, ServiceMetrics* metrics,
                                 MemoryBudget* budget)
    : options_(std::move(options)), pool_(pool), metrics_(metrics), budget_(budget) {
  sweeper_ = std::thread([this] { SweepLoop(); });
}

SessionRegistry::~SessionRegistry() {
  {
    MutexLock lock(&mutex_);
    stopping_ = true;
  }
  sweep_wake_.notify_all();
  sweeper_.join();
  for (const auto& host : Snapshot()) {
    host->Close(grpc::Status(grpc::StatusCode::UNAVAILABLE, "server shutting down"));
  }
}

StatusOr<std::shared_ptr<SessionHost>> SessionRegistry::Open(const v1::SessionConfig& config) {
  {
    MutexLock lock(&mutex_);
    if (draining_) return Unavailable("server is draining; open the session on another instance");
    if (static_cast<int>(sessions_.size()) >= options_.max_sessions) {
      return ResourceExhausted("server holds its maximum of " + std::to_string(options_.max_sessions) + " sessions");
    }
  }
  auto engine_config = wire::ConfigFromProto(config, options_.policy);
  if (!engine_config.ok()) return engine_config.status();
  MemoryBudget::Charge charge;
  if (budget_ != nullptr) {
    auto charged = budget_->Reserve(SessionChargeBytes(*engine_config), "a session of this config");
    if (!charged.ok()) return charged.status();
    charge = std::move(charged).value();
  }
  // FFT plans, particles: outside the lock.
  auto runner = MakeSessionRunner(*engine_config, metrics_);
  if (!runner.ok()) return runner.status();
  auto token = SecureRandomHex(32);
  if (!token.ok()) return token.status();
  MutexLock lock(&mutex_);
  if (static_cast<int>(sessions_.size()) >= options_.max_sessions) {
    return ResourceExhausted("server holds its maximum of " + std::to_string(options_.max_sessions) + " sessions");
  }
  std::string id;
  do {
    auto drawn = SecureRandomHex(16);
    if (!drawn.ok()) return drawn.status();
    id = *std::move(drawn);
  } while (sessions_.count(id) != 0);
  // A session that finishes (the client half-closed, all written) is forgotten before its
  // stream sees OK; the host calls this with its lock held (lock order: host -> registry).
  auto forget = [this, id](const v1::SessionInfo& info) { Forget(id, "finished", info); };
  auto host = std::make_shared<SessionHost>(id, *token, config.label(), std::move(runner).value(), options_.host, pool_,
                                            metrics_, std::move(forget), std::move(charge));
  sessions_[id] = host;
  return host;
}

StatusOr<std::shared_ptr<SessionHost>> SessionRegistry::Find(const std::string& id, const std::string& token) const {
  LOCALIZER_RETURN_IF_ERROR(CheckSessionRef(id, token));
  MutexLock lock(&mutex_);
  if (draining_) return Unavailable("server is draining");
  const auto it = sessions_.find(id);
  if (it == sessions_.end()) return NotFound("no session '" + wire::Escape(id) + "' (unknown, closed or expired)");
  if (!it->second->TokenMatches(token)) return PermissionDenied("wrong resume_token for session " + id);
  return it->second;
}

void SessionRegistry::Remove(const std::string& id, const std::string& reason, const grpc::Status& status) {
  std::shared_ptr<SessionHost> host;
  {
    MutexLock lock(&mutex_);
    const auto it = sessions_.find(id);
    if (it == sessions_.end()) return;
    host = std::move(it->second);
    sessions_.erase(it);
  }
  if (auto* c = metrics_->sessions_closed(reason)) c->Increment();
  LogEvent("info", "session_closed", {{"session", id}, {"reason", reason}});
  host->Close(status);
  if (options_.on_retired) options_.on_retired(*host, host->Info(Clock::now(), options_.ttl_s), reason);
}

void SessionRegistry::Forget(const std::string& id, const std::string& reason, const v1::SessionInfo& info) {
  std::shared_ptr<SessionHost> host;  // the caller (the session itself) holds another reference
  {
    MutexLock lock(&mutex_);
    const auto it = sessions_.find(id);
    if (it == sessions_.end()) return;
    host = std::move(it->second);
    sessions_.erase(it);
  }
  if (auto* c = metrics_->sessions_closed(reason)) c->Increment();
  LogEvent("info", "session_closed", {{"session", id}, {"reason", reason}});
  if (options_.on_retired) options_.on_retired(*host, info, reason);
}

StatusOr<uint64_t> SessionRegistry::Close(const std::string& id, const std::string& token) {
  LOCALIZER_RETURN_IF_ERROR(CheckSessionRef(id, token));
  std::shared_ptr<SessionHost> host;
  {
    MutexLock lock(&mutex_);
    const auto it = sessions_.find(id);
    if (it == sessions_.end()) return NotFound("no session '" + wire::Escape(id) + "'");
    if (!it->second->TokenMatches(token)) return PermissionDenied("wrong resume_token for session " + id);
    host = it->second;
  }
  const uint64_t frames = host->Info(Clock::now(), options_.ttl_s).frames_processed();
  Remove(id, "closed", grpc::Status(grpc::StatusCode::CANCELLED, "session closed by CloseSession"));
  return frames;
}

std::vector<std::shared_ptr<SessionHost>> SessionRegistry::Snapshot() const {
  MutexLock lock(&mutex_);
  std::vector<std::shared_ptr<SessionHost>> hosts;
  for (const auto& [id, host] : sessions_) hosts.push_back(host);
  return hosts;
}

std::vector<v1::SessionInfo> SessionRegistry::List() const {
  const auto now = Clock::now();
  std::vector<v1::SessionInfo> infos;
  for (const auto& host : Snapshot()) infos.push_back(host->Info(now, options_.ttl_s));
  return infos;
}

void SessionRegistry::StartDrain() {
  MutexLock lock(&mutex_);
  draining_ = true;
}

namespace {

// glibc keeps the pages of freed memory in its (per-thread) arenas: after a burst -- a stall
// that queued blocks, many sessions opening at once -- the resident size stays at the burst's
// peak although the memory is free, which reads as growth on a dashboard. Handing free pages
// back now and then keeps RSS a measure of memory in use. It runs on this housekeeping
// thread; while it walks an arena, a session thread allocating there waits.
void ReturnFreeMemoryToTheSystem() {
#if defined(__GLIBC__)
  const auto start = Clock::now();
  malloc_trim(0);
  LogEvent("debug", "memory_trim",
           {{"ms", std::to_string(1e3 * std::chrono::duration<double>(Clock::now() - start).count())}});
#endif
}

}  // namespace

void SessionRegistry::SweepLoop() {
  auto last_trim = Clock::now();
  for (;;) {
    {
      MutexLock lock(&mutex_);
      if (!stopping_) mutex_.WaitFor(&sweep_wake_, std::chrono::milliseconds(250));
      if (stopping_) return;
    }
    if (options_.memory_trim_s > 0.0 &&
        std::chrono::duration<double>(Clock::now() - last_trim).count() >= options_.memory_trim_s) {
      ReturnFreeMemoryToTheSystem();
      last_trim = Clock::now();
    }
    const auto now = Clock::now();
    std::vector<std::pair<std::string, SessionHost::Expiry>> expired;
    for (const auto& host : Snapshot()) {
      const SessionHost::Expiry expiry = host->ExpiryAt(now, options_.ttl_s, options_.idle_s);
      if (expiry != SessionHost::Expiry::kNone) expired.emplace_back(host->id(), expiry);
    }
    for (const auto& [id, expiry] : expired) {
      if (expiry == SessionHost::Expiry::kDetached) {
        Remove(id, "expired", grpc::Status(grpc::StatusCode::NOT_FOUND, "session expired"));
      } else {
        Remove(id, "idle",
               grpc::Status(grpc::StatusCode::DEADLINE_EXCEEDED,
                            "no request for " + ShortSeconds(options_.idle_s) +
                                " s: the session is closed (--session-idle-timeout)"));
      }
    }
  }
}

}  // namespace localizer::server
