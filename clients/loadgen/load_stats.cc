#include "clients/loadgen/load_stats.h"

namespace localizer::loadgen {

void LoadStats::NoteSend(int64_t now_ns) {
  blocks_sent.fetch_add(1, std::memory_order_relaxed);
  int64_t first = first_send_ns.load(std::memory_order_relaxed);
  while ((first < 0 || now_ns < first) &&
         !first_send_ns.compare_exchange_weak(first, now_ns, std::memory_order_relaxed)) {
  }
  Max(&last_send_ns, now_ns);
}

void LoadStats::Max(std::atomic<int64_t>* value, int64_t candidate) {
  int64_t seen = value->load(std::memory_order_relaxed);
  while (candidate > seen && !value->compare_exchange_weak(seen, candidate, std::memory_order_relaxed)) {
  }
}

int64_t LoadStats::Sum(const Tally& tally) {
  int64_t total = 0;
  for (const auto& [name, count] : tally) total += count;
  return total;
}

void LoadStats::Increment(Tally* tally, const std::string& key) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++(*tally)[key];
}

Tally LoadStats::Copy(const Tally& tally) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return tally;
}

}  // namespace localizer::loadgen
