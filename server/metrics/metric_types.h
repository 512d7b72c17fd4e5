// The three metric kinds of the registry, in the shape of prometheus-cpp: Counter, Gauge and
// Histogram. Each is one time series (one set of label values); Family<T> (family.h) holds
// the series of one metric name, and Registry (registry.h) owns the families.
//
// Thread-safety: every method of every class here may be called from any number of threads
// at once. Updates are lock-free (std::atomic<double> and std::atomic<uint64_t>, no mutex,
// no allocation), so hot paths (several observations per audio frame) may call them freely.
// Reads (value(), Snapshot()) are lock-free too and see every update that happened before
// them; a read racing with updates sees some of those updates and not others.
//
// Units are the caller's: name the metric with its unit (`..._seconds`, `..._bytes`) and
// pass values in that unit. Latencies are observed in seconds.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

namespace localizer::server::metrics {

// A monotonically non-decreasing total, starting at 0 (requests served, blocks rejected).
// Cost: one compare-exchange loop on a double (a handful of ns uncontended).
class Counter final {
 public:
  Counter() = default;
  Counter(const Counter&) = delete;
  Counter& operator=(const Counter&) = delete;

  // Adds `amount`. An amount that is negative, NaN or infinite is ignored and the value
  // stays as it was: a counter never decreases and never becomes non-finite.
  void Increment(double amount = 1.0);
  // The total so far.
  double value() const { return value_.load(std::memory_order_relaxed); }

 private:
  std::atomic<double> value_{0.0};
};

// A value that goes up and down (queue depth, active sessions, a temperature), starting at 0.
// Any double is accepted, NaN and infinities included (they serialise as NaN, +Inf, -Inf).
class Gauge final {
 public:
  Gauge() = default;
  Gauge(const Gauge&) = delete;
  Gauge& operator=(const Gauge&) = delete;

  void Set(double value) { value_.store(value, std::memory_order_relaxed); }
  // Adds `delta` (may be negative) atomically with respect to other Add/Increment/Decrement.
  void Add(double delta);
  void Increment(double amount = 1.0) { Add(amount); }
  void Decrement(double amount = 1.0) { Add(-amount); }
  double value() const { return value_.load(std::memory_order_relaxed); }

 private:
  std::atomic<double> value_{0.0};
};

// What a Histogram holds at one instant, in the Prometheus (cumulative) form.
struct HistogramSnapshot {
  // The finite bucket upper bounds, strictly increasing; the +Inf bucket is implicit.
  std::vector<double> upper_bounds;
  // cumulative_counts[i] = observations <= upper_bounds[i] (`le` is inclusive); the last
  // element, at index upper_bounds.size(), is the +Inf bucket and equals `count`.
  std::vector<uint64_t> cumulative_counts;
  double sum = 0.0;    // sum of the observed values (the histogram's unit)
  uint64_t count = 0;  // number of observations
};

// Counts observations into buckets with fixed upper bounds given at construction
// (Prometheus `le` semantics: a value v lands in the first bucket with v <= bound, and in
// +Inf if it exceeds every bound), and keeps their sum and count.
//
// Observe costs a binary search over the bounds (<= 5 comparisons for 20 bounds), one
// atomic increment and one compare-exchange loop on the sum: no lock, no allocation.
// Snapshot is consistent enough for monitoring: its counts are read bucket by bucket, so
// `count` always equals the +Inf cumulative count and every cumulative count is monotone in
// the bucket index, but under concurrent Observe calls `sum` may include an observation
// that the counts do not (or the reverse).
class Histogram final {
 public:
  // `upper_bounds` must be finite and strictly increasing (ValidateBucketBounds says why
  // not); Registry::AddHistogram checks this before it constructs one. It may be empty
  // (only the +Inf bucket).
  explicit Histogram(std::vector<double> upper_bounds);
  Histogram(const Histogram&) = delete;
  Histogram& operator=(const Histogram&) = delete;

  // Records one observation. NaN is ignored (it would poison the sum forever); +/-Inf land
  // in the +Inf / first bucket and make the sum infinite, as in other Prometheus clients.
  void Observe(double value);
  HistogramSnapshot Snapshot() const;
  const std::vector<double>& upper_bounds() const { return upper_bounds_; }

 private:
  const std::vector<double> upper_bounds_;
  // Per-bucket (non-cumulative) counts; index upper_bounds_.size() is the +Inf bucket.
  const std::unique_ptr<std::atomic<uint64_t>[]> bucket_counts_;
  std::atomic<double> sum_{0.0};
};

static_assert(std::atomic<double>::is_always_lock_free);
static_assert(std::atomic<uint64_t>::is_always_lock_free);

}  // namespace localizer::server::metrics
