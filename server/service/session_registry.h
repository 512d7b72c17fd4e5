// The sessions one server instance holds, by id; creates them, finds them for a resume,
// ends them (CloseSession, expiry, shutdown).
//
// A session id is 16 hex digits (64 bits) and its resume token 32 (128 bits), drawn
// independently from the operating system's CSPRNG (secure_random.h): seeing any number of
// ids and tokens tells nothing of another session's. Tokens are compared in constant time. A detached session (its
// stream gone) is kept for `ttl_s`, an attached one that sends nothing for `idle_s` (its stream ends
// DEADLINE_EXCEEDED), then closed by a sweep that runs every ~0.25 s on a thread of its own (which also
// hands the allocator's free pages back to the system every memory_trim_s, so RSS follows the memory in use).
// Thread-safe. Lock order: a session's lock may be held when calling Forget (a session that
// finishes forgets itself); the registry never takes a session's lock while holding its own.
#pragma once

#include <atomic>
#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "localizer/v1/localizer.pb.h"
#include "server/service/memory_budget.h"
#include "server/service/service_metrics.h"
#include "server/service/session_host.h"
#include "server/service/worker_pool.h"
#include "server/sync/mutex.h"
#include "wire/config_wire.h"

namespace localizer::server {

struct RegistryOptions {
  int max_sessions = 1024;
  double ttl_s = 60.0;
  double idle_s = 300.0;        // an attached session with no request for this long is closed; 0: never
  double memory_trim_s = 30.0;  // the sweep returns free heap pages this often; 0: never
  HostLimits host;
  wire::ConfigPolicy policy;
  // Called once for each session that ends (it finished, was closed, expired or went idle;
  // not at shutdown), after it left the registry, with its final counters and the reason
  // (the closed-sessions metric's label): the live view keeps it (finished_sessions.h). It
  // may run with the session's lock held, so it must not call the session's locking methods.
  std::function<void(const SessionHost&, const v1::SessionInfo&, const std::string& reason)> on_retired;
};

class SessionRegistry final {
 public:
  // `budget` (may be null: nothing charged) is charged each session's engine memory and
  // resume history (session_charge.h) for as long as the session lives.
  SessionRegistry(RegistryOptions options, WorkerPool* pool, ServiceMetrics* metrics, MemoryBudget* budget = nullptr);
  ~SessionRegistry();  // stops the sweep; closes every session
  SessionRegistry(const SessionRegistry&) = delete;
  SessionRegistry& operator=(const SessionRegistry&) = delete;

  // INVALID_ARGUMENT naming the field; FAILED_PRECONDITION (backend gpu without one);
  // RESOURCE_EXHAUSTED at max_sessions or when its memory does not fit the budget (checked
  // before the session is built); UNAVAILABLE while draining.
  StatusOr<std::shared_ptr<SessionHost>> Open(const v1::SessionConfig& config) EXCLUDES(mutex_);
  // NOT_FOUND unknown or expired; PERMISSION_DENIED wrong token; UNAVAILABLE draining.
  StatusOr<std::shared_ptr<SessionHost>> Find(const std::string& id, const std::string& token) const EXCLUDES(mutex_);
  // Removes and closes; `reason` labels the closed-sessions metric. No-op if unknown.
  void Remove(const std::string& id, const std::string& reason, const grpc::Status& status) EXCLUDES(mutex_);
  // Removes without touching the session (the session itself calls this as it finishes,
  // with its final counters).
  void Forget(const std::string& id, const std::string& reason, const v1::SessionInfo& info) EXCLUDES(mutex_);
  // CloseSession: NOT_FOUND / PERMISSION_DENIED as Find; returns frames processed.
  StatusOr<uint64_t> Close(const std::string& id, const std::string& token) EXCLUDES(mutex_);

  std::vector<v1::SessionInfo> List() const EXCLUDES(mutex_);

  // Refuse new sessions and resumes from now on (UNAVAILABLE).
  void StartDrain() EXCLUDES(mutex_);
  std::vector<std::shared_ptr<SessionHost>> Snapshot() const EXCLUDES(mutex_);

 private:
  void SweepLoop() EXCLUDES(mutex_);

  const RegistryOptions options_;
  WorkerPool* const pool_;
  ServiceMetrics* const metrics_;
  MemoryBudget* const budget_;

  mutable Mutex mutex_;
  std::map<std::string, std::shared_ptr<SessionHost>> sessions_ GUARDED_BY(mutex_);
  bool draining_ GUARDED_BY(mutex_) = false;
  bool stopping_ GUARDED_BY(mutex_) = false;
  std::condition_variable sweep_wake_;
  std::thread sweeper_;
};

}  // namespace localizer::server
