// Registry: owns metric families and writes them in the Prometheus text format.
//
//   Registry registry;
//   Family<Histogram>* latency = registry.AddHistogram(
//       "localizer_stage_latency_seconds", "Time spent per stage and block.", {"stage"},
//       DefaultLatencyBucketsSeconds()).value();
//   Histogram* gcc = latency->WithLabels({"gcc_phat"}).value();  // once, then cached
//   gcc->Observe(elapsed_s);                                     // per block, lock-free
//   registry.AddCollector([&] { depth->Set(queue.size()); });    // refreshed per scrape
//   std::string text = registry.Serialize();                     // what /metrics serves
//
// Names: metric names must match [a-zA-Z_:][a-zA-Z0-9_:]*, label names
// [a-zA-Z_][a-zA-Z0-9_]* without a leading "__", histograms may not use the label "le"
// (names.h). Put the unit in the name (`_seconds`, `_bytes`) and end counters in `_total`
// (promtool's lint asks for both). Help text is required, any UTF-8.
//
// A histogram named N also produces the series N_bucket, N_sum and N_count; no two
// families may produce a series of the same name, so e.g. a gauge "x_count" and a
// histogram "x" cannot both be registered.
//
// Lifetime: every Family and every series pointer handed out stays valid until the Registry
// is destroyed; nothing is ever unregistered. The Registry is neither copyable nor movable.
//
// Thread-safety: all methods may be called concurrently from any threads. Add* and
// Serialize share one mutex (held briefly); each family has its own mutex for WithLabels;
// metric updates are lock-free. Collectors run serially (under a mutex of their own), on
// the thread that calls Collect or Serialize.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "engine/core/status.h"
#include "server/metrics/family.h"
#include "server/metrics/metric_family.h"
#include "server/metrics/metric_types.h"
#include "server/sync/mutex.h"

namespace localizer::server::metrics {

// `count` bucket upper bounds start, start*factor, start*factor^2, ... (each computed by
// one more multiplication). Needs start > 0, factor > 1, count >= 1 and every bound finite;
// otherwise returns an empty list, which AddHistogram rejects with INVALID_ARGUMENT.
std::vector<double> ExponentialBuckets(double start, double factor, int count);

// Latency bucket upper bounds in seconds, 1-2.5-5 per decade from 10 us to 1 s:
// 1e-5, 2.5e-5, 5e-5, 1e-4, 2.5e-4, 5e-4, 1e-3, 2.5e-3, 5e-3, 0.01, 0.025, 0.05, 0.1,
// 0.25, 0.5, 1 (16 bounds; slower observations land in +Inf).
std::vector<double> DefaultLatencyBucketsSeconds();

class Registry final {
 public:
  Registry();
  ~Registry();
  Registry(const Registry&) = delete;
  Registry& operator=(const Registry&) = delete;

  // Each Add* registers a new family and returns it (owned by the Registry), or
  // INVALID_ARGUMENT naming the problem: an invalid metric or label name, a repeated label
  // name, empty or non-UTF-8 help, a name already registered or clashing with a
  // histogram's _bucket/_sum/_count series, or (histograms) bounds that are empty,
  // non-finite or not strictly increasing. A failed Add changes nothing.
  StatusOr<Family<Counter>*> AddCounter(const std::string& name, const std::string& help,
                                        const std::vector<std::string>& label_names = {});
  StatusOr<Family<Gauge>*> AddGauge(const std::string& name, const std::string& help,
                                    const std::vector<std::string>& label_names = {});
  // `bucket_upper_bounds`: finite, strictly increasing, in the metric's unit; the +Inf
  // bucket is added implicitly. See ExponentialBuckets and DefaultLatencyBucketsSeconds.
  StatusOr<Family<Histogram>*> AddHistogram(const std::string& name, const std::string& help,
                                            const std::vector<std::string>& label_names,
                                            std::vector<double> bucket_upper_bounds);

  // Registers a hook run at the start of every Collect/Serialize, before any family is
  // read: refresh gauges whose value is cheaper to read at scrape time than to track
  // (queue depth, sessions open). Hooks run in registration order, one scrape at a time,
  // on the scraping thread (an HTTP worker), so they must be thread-safe with respect to
  // the rest of the program. A hook may update metrics and call WithLabels or Add*, but
  // must not call AddCollector, Collect or Serialize (that would deadlock), and must not
  // throw.
  void AddCollector(std::function<void()> collector) EXCLUDES(collectors_mutex_);

  // Runs the collectors, then snapshots every family, sorted by name; series within a
  // family are sorted by label values.
  std::vector<MetricFamily> Collect() const EXCLUDES(collectors_mutex_, mutex_);

  // Collect() written in the text exposition format 0.0.4 (text_format.h).
  std::string Serialize() const;

 private:
  template <typename T>
  StatusOr<Family<T>*> Add(const std::string& name, const std::string& help,
                           const std::vector<std::string>& label_names, std::vector<double> bucket_upper_bounds)
      EXCLUDES(mutex_);

  // Taken after collectors_mutex_ (Collect holds that one while the collectors run, and
  // they may register metrics).
  mutable Mutex mutex_ ACQUIRED_AFTER(collectors_mutex_);
  // Family name -> family, sorted by name.
  std::map<std::string, std::unique_ptr<Collectable>> families_ GUARDED_BY(mutex_);
  // Every series name a family writes (its own name; a histogram's _bucket, _sum and
  // _count too) -> the family's name.
  std::map<std::string, std::string> series_names_ GUARDED_BY(mutex_);

  mutable Mutex collectors_mutex_;
  std::vector<std::function<void()>> collectors_ GUARDED_BY(collectors_mutex_);
};

}  // namespace localizer::server::metrics
