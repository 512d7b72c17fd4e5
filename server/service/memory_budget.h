// The memory the server has promised, against a budget (--memory-budget-mib): admission by
// cost. A session is charged what its engine state will hold (engine/pipeline/
// session_memory.h: particles, frames, FFT plans, tracks) and the estimates the server keeps
// for its resume (session_charge.h) when it opens, and a Locate call
// what its one large frame needs, for as long as it runs; what does not fit is refused
// RESOURCE_EXHAUSTED naming the cost, the use and the budget, before anything is allocated.
// A charge is returned when its Charge is destroyed (the session closed, the call finished).
//
// The budget bounds what the sessions hold, not the transport: gRPC's own buffers are bounded
// by its resource quota (transport_limits.h), queued blocks by --max-queue-blocks.
// Thread-safe.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "engine/core/status.h"

namespace localizer::server {

class MemoryBudget {
 public:
  // A held share of the budget; returned on destruction. Move-only.
  class Charge {
   public:
    Charge() = default;
    Charge(Charge&& other) noexcept : budget_(other.budget_), bytes_(other.bytes_) { other.budget_ = nullptr; }
    Charge& operator=(Charge&& other) noexcept;
    Charge(const Charge&) = delete;
    Charge& operator=(const Charge&) = delete;
    ~Charge() { Release(); }
    int64_t bytes() const { return budget_ != nullptr ? bytes_ : 0; }

   private:
    friend class MemoryBudget;
    Charge(MemoryBudget* budget, int64_t bytes) : budget_(budget), bytes_(bytes) {}
    void Release();
    MemoryBudget* budget_ = nullptr;
    int64_t bytes_ = 0;
  };

  // budget_bytes <= 0: no limit (every Reserve succeeds; use is still counted).
  explicit MemoryBudget(int64_t budget_bytes) : budget_bytes_(budget_bytes) {}

  // A charge of `bytes` for `what` ("session", "Locate"), or RESOURCE_EXHAUSTED ("a session
  // of this config needs 2150 MiB; 7900 of 8192 MiB are in use (--memory-budget-mib)").
  StatusOr<Charge> Reserve(int64_t bytes, const std::string& what);

  int64_t used_bytes() const { return used_bytes_.load(std::memory_order_relaxed); }
  int64_t budget_bytes() const { return budget_bytes_; }

 private:
  const int64_t budget_bytes_;
  std::atomic<int64_t> used_bytes_{0};
};

// The default budget: 3/4 of the memory this process may use -- the cgroup's memory.max
// (cgroup v2, or v1's memory.limit_in_bytes) when set, else the machine's MemTotal.
int64_t DefaultMemoryBudgetBytes();

}  // namespace localizer::server
