#include "clients/loadgen/latency_histogram.h"

#include <algorithm>
#include <cmath>

namespace localizer::loadgen {

namespace {

constexpr double kFirstEdgeS = 1e-6;
const double kLogRatio = std::log(1.01);

}  // namespace

int LatencyHistogram::BucketOf(double latency_s) {
  if (!(latency_s > kFirstEdgeS)) return 0;
  // Smallest b with 1.01^b >= latency / 1 us; the epsilon keeps an exact edge in its bucket.
  const double b = std::ceil(std::log(latency_s / kFirstEdgeS) / kLogRatio - 1e-9);
  return static_cast<int>(std::min<double>(b, kLatencyBuckets - 1));
}

double LatencyHistogram::UpperEdge(int bucket) { return kFirstEdgeS * std::exp(bucket * kLogRatio); }

void LatencyHistogram::Add(double latency_s) {
  if (!std::isfinite(latency_s) || latency_s < 0.0) return;
  buckets_[BucketOf(latency_s)].fetch_add(1, std::memory_order_relaxed);
  const auto ns = static_cast<uint64_t>(latency_s * 1e9);
  uint64_t seen = max_ns_.load(std::memory_order_relaxed);
  while (ns > seen && !max_ns_.compare_exchange_weak(seen, ns, std::memory_order_relaxed)) {
  }
}

LatencyCounts LatencyHistogram::Snapshot() const {
  LatencyCounts counts;
  for (int b = 0; b < kLatencyBuckets; ++b) {
    counts.buckets[b] = buckets_[b].load(std::memory_order_relaxed);
    counts.count += counts.buckets[b];
  }
  counts.max_s = 1e-9 * static_cast<double>(max_ns_.load(std::memory_order_relaxed));
  return counts;
}

double LatencyCounts::Quantile(double q) const {
  if (count == 0) return 0.0;
  // Nearest rank: the ceil(q n)-th smallest (1-based), at least the first.
  const auto rank = std::max<uint64_t>(1, static_cast<uint64_t>(std::ceil(q * static_cast<double>(count))));
  uint64_t seen = 0;
  for (int b = 0; b < kLatencyBuckets; ++b) {
    seen += buckets[b];
    if (seen >= rank) return std::min(LatencyHistogram::UpperEdge(b), max_s);
  }
  return max_s;
}

LatencyCounts LatencyCounts::Minus(const LatencyCounts& earlier) const {
  LatencyCounts out;
  for (int b = 0; b < kLatencyBuckets; ++b) {
    out.buckets[b] = buckets[b] - std::min(buckets[b], earlier.buckets[b]);
    out.count += out.buckets[b];
  }
  out.max_s = max_s;
  return out;
}

}  // namespace localizer::loadgen
