#include "server/service/memory_budget.h"

#include <algorithm>
#include <fstream>
#include <string>

namespace localizer::server {
namespace {

constexpr int64_t kMiB = int64_t{1} << 20;

std::string MiB(int64_t bytes) { return std::to_string((bytes + kMiB - 1) / kMiB); }

// A whole number from the first line of `path`, or 0 ("max", missing, unreadable).
int64_t ReadLimit(const char* path) {
  std::ifstream in(path);
  std::string word;
  if (!(in >> word) || word.empty() || word.find_first_not_of("0123456789") != std::string::npos) return 0;
  try {
    return static_cast<int64_t>(std::stoll(word));
  } catch (...) {
    return 0;  // out of range: no limit worth the name
  }
}

int64_t MemTotalBytes() {
  std::ifstream in("/proc/meminfo");
  std::string key, unit;
  int64_t kib = 0;
  while (in >> key >> kib >> unit) {
    if (key == "MemTotal:") return kib * 1024;
  }
  return 0;
}

}  // namespace

MemoryBudget::Charge& MemoryBudget::Charge::operator=(Charge&& other) noexcept {
  if (this != &other) {
    Release();
    budget_ = other.budget_;
    bytes_ = other.bytes_;
    other.budget_ = nullptr;
  }
  return *this;
}

void MemoryBudget::Charge::Release() {
  if (budget_ != nullptr) budget_->used_bytes_.fetch_sub(bytes_, std::memory_order_relaxed);
  budget_ = nullptr;
}

StatusOr<MemoryBudget::Charge> MemoryBudget::Reserve(int64_t bytes, const std::string& what) {
  bytes = std::max<int64_t>(bytes, 0);
  int64_t used = used_bytes_.load(std::memory_order_relaxed);
  for (;;) {
    if (budget_bytes_ > 0 && (bytes > budget_bytes_ - used)) {
      return ResourceExhausted(what + " needs " + MiB(bytes) + " MiB; " + MiB(used) + " of " + MiB(budget_bytes_) +
                               " MiB are in use (--memory-budget-mib)");
    }
    if (used_bytes_.compare_exchange_weak(used, used + bytes, std::memory_order_relaxed)) break;
  }
  return Charge(this, bytes);
}

int64_t DefaultMemoryBudgetBytes() {
  int64_t limit = MemTotalBytes();
  for (const char* path : {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"}) {
    const int64_t cgroup = ReadLimit(path);
    // v1 reports "no limit" as a huge number: only a limit below the machine's counts.
    if (cgroup > 0 && (limit == 0 || cgroup < limit)) limit = cgroup;
  }
  return limit / 4 * 3;
}

}  // namespace localizer::server
