#include "server/metrics/family.h"

#include <type_traits>
#include <utility>

#include "server/metrics/names.h"

namespace localizer::server::metrics {
namespace {

template <typename T>
constexpr MetricType kTypeOf = std::is_same_v<T, Counter> ? MetricType::kCounter
                               : std::is_same_v<T, Gauge> ? MetricType::kGauge
                                                          : MetricType::kHistogram;

}  // namespace

template <typename T>
Family<T>::Family(std::string name, std::string help, std::vector<std::string> label_names,
                  std::vector<double> bucket_upper_bounds)
    : name_(std::move(name)),
      help_(std::move(help)),
      label_names_(std::move(label_names)),
      bucket_upper_bounds_(std::move(bucket_upper_bounds)) {}

template <typename T>
StatusOr<T*> Family<T>::WithLabels(const std::vector<std::string>& label_values) {
  if (label_values.size() != label_names_.size()) {
    return InvalidArgument("metric \"" + name_ + "\" has " + std::to_string(label_names_.size()) + " label(s), got " +
                           std::to_string(label_values.size()) + " value(s)");
  }
  for (size_t i = 0; i < label_values.size(); ++i) {
    if (!IsValidUtf8(label_values[i])) {
      return InvalidArgument("metric \"" + name_ + "\": value of label \"" + label_names_[i] + "\" is not valid UTF-8");
    }
  }
  MutexLock lock(&mutex_);
  std::unique_ptr<T>& series = series_[label_values];
  if (!series) {
    if constexpr (std::is_same_v<T, Histogram>) {
      series = std::make_unique<Histogram>(bucket_upper_bounds_);
    } else {
      series = std::make_unique<T>();
    }
  }
  return series.get();
}

template <typename T>
MetricFamily Family<T>::Collect() const {
  MetricFamily family;
  family.name = name_;
  family.help = help_;
  family.type = kTypeOf<T>;
  MutexLock lock(&mutex_);
  family.points.reserve(series_.size());
  for (const auto& [label_values, series] : series_) {
    MetricPoint& point = family.points.emplace_back();
    point.labels.reserve(label_values.size());
    for (size_t i = 0; i < label_values.size(); ++i) {
      point.labels.push_back({label_names_[i], label_values[i]});
    }
    if constexpr (std::is_same_v<T, Histogram>) {
      point.histogram = series->Snapshot();
    } else {
      point.value = series->value();
    }
  }
  return family;
}

template class Family<Counter>;
template class Family<Gauge>;
template class Family<Histogram>;

}  // namespace localizer::server::metrics
