#include "server/metrics/text_format.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>

namespace localizer::server::metrics {
namespace {

void AppendNumber(double value, std::string* out) {
  if (std::isnan(value)) {
    out->append("NaN");
  } else if (std::isinf(value)) {
    out->append(value > 0 ? "+Inf" : "-Inf");
  } else {
    char buffer[64];
    char* const end = buffer + sizeof buffer;
    constexpr double kTwoTo53 = 9007199254740992.0;  // every integer below is exact
    if (value == std::trunc(value) && std::abs(value) < kTwoTo53) {
      out->append(buffer, std::to_chars(buffer, end, static_cast<int64_t>(value)).ptr);
      return;
    }
    // Shortest round-trip digits, laid out as Go's strconv.FormatFloat(v, 'g', -1, 64)
    // (what Prometheus' own client writes): exponent form when the decimal exponent is
    // below -4 or at least 6, plain decimals otherwise.
    const std::to_chars_result scientific = std::to_chars(buffer, end, value, std::chars_format::scientific);
    const char* e = std::find(buffer, scientific.ptr, 'e');
    int exponent = 0;
    std::from_chars(e + 1 + (e[1] == '+' ? 1 : 0), scientific.ptr, exponent);
    if (exponent < -4 || exponent >= 6) {
      out->append(buffer, scientific.ptr);
    } else {
      out->append(buffer, std::to_chars(buffer, end, value, std::chars_format::fixed).ptr);
    }
  }
}

// `{a="x",b="y"` with an optional extra label (histograms' `le`) and the closing brace;
// nothing at all when there are no labels.
void AppendLabels(const std::vector<LabelPair>& labels, const char* extra_name, std::string_view extra_value,
                  std::string* out) {
  if (labels.empty() && extra_name == nullptr) return;
  out->push_back('{');
  bool first = true;
  for (const LabelPair& label : labels) {
    if (!first) out->push_back(',');
    first = false;
    out->append(label.name).append("=\"").append(EscapeLabelValue(label.value)).push_back('"');
  }
  if (extra_name != nullptr) {
    if (!first) out->push_back(',');
    out->append(extra_name).append("=\"").append(extra_value).push_back('"');
  }
  out->push_back('}');
}

void AppendSample(std::string_view name, std::string_view suffix, const std::vector<LabelPair>& labels,
                  const char* extra_name, std::string_view extra_value, double value, std::string* out) {
  out->append(name).append(suffix);
  AppendLabels(labels, extra_name, extra_value, out);
  out->push_back(' ');
  AppendNumber(value, out);
  out->push_back('\n');
}

void AppendHistogram(const MetricFamily& family, const MetricPoint& point, std::string* out) {
  const HistogramSnapshot& h = point.histogram;
  for (size_t i = 0; i < h.upper_bounds.size() && i < h.cumulative_counts.size(); ++i) {
    AppendSample(family.name, "_bucket", point.labels, "le", FormatNumber(h.upper_bounds[i]),
                 static_cast<double>(h.cumulative_counts[i]), out);
  }
  AppendSample(family.name, "_bucket", point.labels, "le", "+Inf", static_cast<double>(h.count), out);
  AppendSample(family.name, "_sum", point.labels, nullptr, {}, h.sum, out);
  AppendSample(family.name, "_count", point.labels, nullptr, {}, static_cast<double>(h.count), out);
}

}  // namespace

const char* MetricTypeName(MetricType type) {
  switch (type) {
    case MetricType::kCounter:
      return "counter";
    case MetricType::kGauge:
      return "gauge";
    case MetricType::kHistogram:
      return "histogram";
  }
  return "untyped";
}

std::string FormatNumber(double value) {
  std::string out;
  AppendNumber(value, &out);
  return out;
}

std::string EscapeLabelValue(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '\\':
        out.append("\\\\");
        break;
      case '"':
        out.append("\\\"");
        break;
      case '\n':
        out.append("\\n");
        break;
      default:
        out.push_back(c);
    }
  }
  return out;
}

std::string EscapeHelp(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '\\':
        out.append("\\\\");
        break;
      case '\n':
        out.append("\\n");
        break;
      default:
        out.push_back(c);
    }
  }
  return out;
}

std::string SerializeTextFormat(const std::vector<MetricFamily>& families) {
  std::string out;
  for (const MetricFamily& family : families) {
    out.append("# HELP ").append(family.name).push_back(' ');
    out.append(EscapeHelp(family.help)).push_back('\n');
    out.append("# TYPE ").append(family.name).push_back(' ');
    out.append(MetricTypeName(family.type)).push_back('\n');
    for (const MetricPoint& point : family.points) {
      if (family.type == MetricType::kHistogram) {
        AppendHistogram(family, point, &out);
      } else {
        AppendSample(family.name, "", point.labels, nullptr, {}, point.value, &out);
      }
    }
  }
  return out;
}

}  // namespace localizer::server::metrics
