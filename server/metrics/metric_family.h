// Plain values that describe metrics at one instant (prometheus-cpp's
// `client_metric.h` / `metric_family.h` / `collectable.h` shape). A Collectable turns live
// metrics into these; text_format.h writes them out. Nothing here is shared or atomic.
#pragma once

#include <string>
#include <vector>

#include "server/metrics/metric_types.h"

namespace localizer::server::metrics {

enum class MetricType { kCounter, kGauge, kHistogram };

// "counter", "gauge", "histogram": the word the `# TYPE` line uses.
const char* MetricTypeName(MetricType type);

struct LabelPair {
  std::string name;
  std::string value;  // any UTF-8; escaped by the serialiser
};

// One time series of a family: its label values and its current value.
struct MetricPoint {
  std::vector<LabelPair> labels;  // in the family's label-name order
  double value = 0.0;             // counter or gauge value; unused for histograms
  HistogramSnapshot histogram;    // histograms only
};

// All series of one metric name.
struct MetricFamily {
  std::string name;
  std::string help;
  MetricType type = MetricType::kGauge;
  std::vector<MetricPoint> points;  // in a stable order (sorted by label values)
};

// Something that can report metric families (a Family<T>, a Registry).
// Collect may be called from any thread; implementations must be thread-safe.
class Collectable {
 public:
  virtual ~Collectable() = default;
  virtual MetricFamily Collect() const = 0;
};

}  // namespace localizer::server::metrics
