// Family<T>: all time series of one metric name that differ only by label values, e.g.
//   localizer_blocks_total{backend="cpu"} and localizer_blocks_total{backend="gpu"}.
// T is Counter, Gauge or Histogram (metric_types.h); families are created by the Registry
// (registry.h), which validates the name, help and label names and owns the family.
//
// Usage on a hot path: look a series up once, keep the pointer, update through it:
//   Counter* rejected = blocks_family->WithLabels({"cpu", "rejected"}).value();
//   ... per block: rejected->Increment();
// WithLabels takes the family's mutex (a map lookup, and an allocation the first time a
// label combination is seen); updates through the returned pointer take no lock.
//
// Lifetime: a series, once created, is never removed; the pointer WithLabels returns stays
// valid until the owning Registry is destroyed. Keep label values to small bounded sets
// (a backend name, a status), never per-session or per-request ids: each distinct
// combination is a series kept in memory and exported on every scrape.
//
// Thread-safety: all methods may be called concurrently from any threads.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "engine/core/status.h"
#include "server/metrics/metric_family.h"
#include "server/metrics/metric_types.h"
#include "server/sync/mutex.h"

namespace localizer::server::metrics {

class Registry;

template <typename T>
class Family final : public Collectable {
 public:
  Family(const Family&) = delete;
  Family& operator=(const Family&) = delete;

  // The series with these label values, one per label name and in the same order, created
  // at zero on first use. Values may be any UTF-8 text, the empty string included.
  // INVALID_ARGUMENT if the number of values differs from the number of label names or a
  // value is not valid UTF-8.
  StatusOr<T*> WithLabels(const std::vector<std::string>& label_values) EXCLUDES(mutex_);

  const std::string& name() const { return name_; }
  const std::string& help() const { return help_; }
  const std::vector<std::string>& label_names() const { return label_names_; }

  // The family's series sorted by label values (lexicographically, in label-name order).
  MetricFamily Collect() const override EXCLUDES(mutex_);

 private:
  friend class Registry;
  // Arguments are validated by the Registry. `bucket_upper_bounds` is used by Histogram only.
  Family(std::string name, std::string help, std::vector<std::string> label_names,
         std::vector<double> bucket_upper_bounds);

  const std::string name_;
  const std::string help_;
  const std::vector<std::string> label_names_;
  const std::vector<double> bucket_upper_bounds_;

  mutable Mutex mutex_;
  // Label values -> series. The series themselves are not guarded (atomics).
  std::map<std::vector<std::string>, std::unique_ptr<T>> series_ GUARDED_BY(mutex_);
};

// Defined in family.cc for these three kinds only.
extern template class Family<Counter>;
extern template class Family<Gauge>;
extern template class Family<Histogram>;

}  // namespace localizer::server::metrics
