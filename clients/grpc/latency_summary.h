// Percentiles of per-estimate latencies.
//
// Nearest rank over the n finite values sorted ascending, l_(1) <= ... <= l_(n):
//   pXX = l_(ceil(XX/100 * n)), the smallest latency >= XX % of all latencies
// (the rule `score` uses for p95). Non-finite values (estimates whose block was not sent
// on this stream, e.g. resent after a resume) are left out and counted in `unknown`.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace localizer::client {

struct LatencySummary {
  int64_t count = 0;    // finite latencies summarised
  int64_t unknown = 0;  // non-finite ones left out
  double p50_s = 0.0;
  double p95_s = 0.0;
  double p99_s = 0.0;
  double max_s = 0.0;
};

LatencySummary SummariseLatencies(std::vector<double> latencies_s);

// "latency_ms p50=1.234 p95=2.345 p99=3.456 max=4.567 (n=120)"; "latency_ms n=0" when empty.
std::string FormatLatencyMs(const LatencySummary& summary);

}  // namespace localizer::client
