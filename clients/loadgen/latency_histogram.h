// Latencies in bounded memory: a log-bucketed histogram that many threads add to at once.
//
// A load run of hours at thousands of estimates per second would hold gigabytes of raw
// latencies (latency_summary.h sorts a vector of them); this keeps 2,100 counters instead.
// Bucket b holds latencies in (L_b-1, L_b], L_b = 1 us x 1.01^b, b = 0 .. kBuckets - 1 (the
// last also takes everything above, up to ~1,150 s). Percentiles use the nearest rank rule
// of latency_summary.h, pXX = the smallest latency >= XX % of them, and report the upper
// edge of its bucket capped at the largest latency seen: at most 1 % above the exact value,
// never below it, and p50 <= p95 <= p99 <= max always holds.
//
// Thread safety: Add from any number of threads (relaxed atomic increments); Snapshot at
// any time gives a consistent-enough copy (each counter read once).
#pragma once

#include <array>
#include <atomic>
#include <cstdint>

namespace localizer::loadgen {

inline constexpr int kLatencyBuckets = 2100;

// Counts per bucket, and the extremes; a copy that can be subtracted (the last second's).
struct LatencyCounts {
  std::array<uint64_t, kLatencyBuckets> buckets{};
  uint64_t count = 0;
  double max_s = 0.0;  // of everything added so far (not of a difference)

  // The latency at quantile q in (0, 1], s; 0 when empty.
  double Quantile(double q) const;
  // this - earlier, bucket by bucket (max_s is kept: the max since the start).
  LatencyCounts Minus(const LatencyCounts& earlier) const;
};

class LatencyHistogram {
 public:
  // A finite latency >= 0, seconds; others are ignored.
  void Add(double latency_s);
  LatencyCounts Snapshot() const;

  // The bucket of a latency, and a bucket's upper edge (seconds).
  static int BucketOf(double latency_s);
  static double UpperEdge(int bucket);

 private:
  std::array<std::atomic<uint64_t>, kLatencyBuckets> buckets_{};
  std::atomic<uint64_t> max_ns_{0};
};

}  // namespace localizer::loadgen
