#include "clients/grpc/latency_summary.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace localizer::client {

namespace {

double NearestRank(const std::vector<double>& sorted, double fraction) {
  const auto n = static_cast<double>(sorted.size());
  const auto rank = static_cast<size_t>(std::ceil(fraction * n));
  return sorted[std::clamp<size_t>(rank, 1, sorted.size()) - 1];
}

}  // namespace

LatencySummary SummariseLatencies(std::vector<double> latencies_s) {
  LatencySummary summary;
  const auto finite_end =
      std::partition(latencies_s.begin(), latencies_s.end(), [](double v) { return std::isfinite(v); });
  summary.unknown = latencies_s.end() - finite_end;
  latencies_s.erase(finite_end, latencies_s.end());
  summary.count = static_cast<int64_t>(latencies_s.size());
  if (latencies_s.empty()) return summary;
  std::sort(latencies_s.begin(), latencies_s.end());
  summary.p50_s = NearestRank(latencies_s, 0.50);
  summary.p95_s = NearestRank(latencies_s, 0.95);
  summary.p99_s = NearestRank(latencies_s, 0.99);
  summary.max_s = latencies_s.back();
  return summary;
}

std::string FormatLatencyMs(const LatencySummary& s) {
  if (s.count == 0) return "latency_ms n=0";
  char text[160];
  std::snprintf(text, sizeof(text), "latency_ms p50=%.3f p95=%.3f p99=%.3f max=%.3f (n=%lld)", s.p50_s * 1e3,
                s.p95_s * 1e3, s.p99_s * 1e3, s.max_s * 1e3, static_cast<long long>(s.count));
  return text;
}

}  // namespace localizer::client
