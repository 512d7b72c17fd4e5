#include "server/metrics/registry.h"

#include <cmath>
#include <type_traits>
#include <utility>

#include "server/metrics/names.h"
#include "server/metrics/text_format.h"

namespace localizer::server::metrics {

std::vector<double> ExponentialBuckets(double start, double factor, int count) {
  if (!(start > 0.0) || !(factor > 1.0) || count < 1) return {};
  std::vector<double> bounds;
  bounds.reserve(static_cast<size_t>(count));
  double bound = start;
  for (int i = 0; i < count; ++i) {
    if (!std::isfinite(bound)) return {};
    bounds.push_back(bound);
    bound *= factor;
  }
  return bounds;
}

std::vector<double> DefaultLatencyBucketsSeconds() {
  return {1e-5, 2.5e-5, 5e-5, 1e-4, 2.5e-4, 5e-4, 1e-3, 2.5e-3, 5e-3, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1.0};
}

Registry::Registry() = default;
Registry::~Registry() = default;

template <typename T>
StatusOr<Family<T>*> Registry::Add(const std::string& name, const std::string& help,
                                   const std::vector<std::string>& label_names,
                                   std::vector<double> bucket_upper_bounds) {
  constexpr bool kIsHistogram = std::is_same_v<T, Histogram>;
  LOCALIZER_RETURN_IF_ERROR(ValidateMetricName(name));
  if (Status s = ValidateLabelNames(label_names, kIsHistogram); !s.ok()) {
    return InvalidArgument("metric \"" + name + "\": " + s.message());
  }
  if (help.empty()) return InvalidArgument("metric \"" + name + "\" needs a help text");
  if (!IsValidUtf8(help)) {
    return InvalidArgument("help text of metric \"" + name + "\" is not valid UTF-8");
  }
  if constexpr (kIsHistogram) {
    if (Status s = ValidateBucketBounds(bucket_upper_bounds); !s.ok()) {
      return InvalidArgument("histogram \"" + name + "\": " + s.message());
    }
  }

  std::vector<std::string> series_names = {name};
  if constexpr (kIsHistogram) {
    series_names.push_back(name + "_bucket");
    series_names.push_back(name + "_sum");
    series_names.push_back(name + "_count");
  }

  MutexLock lock(&mutex_);
  if (families_.contains(name)) {
    return InvalidArgument("metric \"" + name + "\" is already registered");
  }
  for (const std::string& series : series_names) {
    if (auto it = series_names_.find(series); it != series_names_.end()) {
      return InvalidArgument("metric \"" + name + "\" would write series \"" + series + "\", which metric \"" +
                             it->second + "\" already writes");
    }
  }
  // The constructor is private to Registry, hence `new` rather than std::make_unique.
  std::unique_ptr<Family<T>> family(new Family<T>(name, help, label_names, std::move(bucket_upper_bounds)));
  Family<T>* const result = family.get();
  families_.emplace(name, std::move(family));
  for (std::string& series : series_names) series_names_.emplace(std::move(series), name);
  return result;
}

StatusOr<Family<Counter>*> Registry::AddCounter(const std::string& name, const std::string& help,
                                                const std::vector<std::string>& label_names) {
  return Add<Counter>(name, help, label_names, {});
}

StatusOr<Family<Gauge>*> Registry::AddGauge(const std::string& name, const std::string& help,
                                            const std::vector<std::string>& label_names) {
  return Add<Gauge>(name, help, label_names, {});
}

StatusOr<Family<Histogram>*> Registry::AddHistogram(const std::string& name, const std::string& help,
                                                    const std::vector<std::string>& label_names,
                                                    std::vector<double> bucket_upper_bounds) {
  return Add<Histogram>(name, help, label_names, std::move(bucket_upper_bounds));
}

void Registry::AddCollector(std::function<void()> collector) {
  MutexLock lock(&collectors_mutex_);
  collectors_.push_back(std::move(collector));
}

std::vector<MetricFamily> Registry::Collect() const {
  {
    MutexLock lock(&collectors_mutex_);
    for (const auto& collector : collectors_) collector();
  }
  std::vector<const Collectable*> families;
  {
    MutexLock lock(&mutex_);
    families.reserve(families_.size());
    for (const auto& [name, family] : families_) families.push_back(family.get());
  }
  // Families are never removed, so the pointers stay valid without the lock; reading them
  // outside it lets a collector or another thread register metrics meanwhile.
  std::vector<MetricFamily> out;
  out.reserve(families.size());
  for (const Collectable* family : families) out.push_back(family->Collect());
  return out;
}

std::string Registry::Serialize() const { return SerializeTextFormat(Collect()); }

}  // namespace localizer::server::metrics
