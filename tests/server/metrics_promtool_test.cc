// The Registry's text output checked by Prometheus' own parser and linter:
// `promtool check metrics` (Debian package `prometheus`) must exit 0 and print nothing.
// Skips, saying why, where promtool is not installed.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <random>
#include <string>

#include "server/metrics/registry.h"

namespace localizer::server::metrics {
namespace {

constexpr char kPromtool[] = "/usr/bin/promtool";

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

CommandResult RunCommand(const std::string& command) {
  CommandResult result;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (pipe == nullptr) return result;
  char buffer[4096];
  size_t n = 0;
  while ((n = fread(buffer, 1, sizeof buffer, pipe)) > 0) result.output.append(buffer, n);
  const int status = pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

// A registry with every metric kind, labels whose values need escaping, help needing
// escaping, special values, and a labelled and an unlabelled histogram.
void Fill(Registry* registry) {
  Family<Counter>* blocks =
      registry->AddCounter("localizer_blocks_total", "Blocks processed.\nBy backend \\ result.", {"backend", "result"})
          .value();
  blocks->WithLabels({"cpu", "ok"}).value()->Increment(1234);
  blocks->WithLabels({"gpu \"cuda\"", "rejected\nbad \\ block"}).value()->Increment(0.5);
  blocks->WithLabels({"", "naïve ☃"}).value()->Increment();

  Family<Gauge>* sessions = registry->AddGauge("localizer_sessions", "Sessions open.", {"tracker"}).value();
  sessions->WithLabels({"particle_filter"}).value()->Set(3);
  sessions->WithLabels({"ekf"}).value()->Set(-1.25e-7);
  sessions->WithLabels({"inf"}).value()->Set(std::numeric_limits<double>::infinity());
  sessions->WithLabels({"nan"}).value()->Set(std::numeric_limits<double>::quiet_NaN());
  registry->AddGauge("localizer_queue_depth", "Blocks waiting.").value()->WithLabels({}).value()->Set(7);

  std::mt19937_64 rng(7);
  std::lognormal_distribution<double> latency_s(std::log(1e-3), 1.5);
  Family<Histogram>* stages = registry
                                  ->AddHistogram("localizer_stage_latency_seconds", "Stage latency per block.",
                                                 {"stage"}, DefaultLatencyBucketsSeconds())
                                  .value();
  for (const char* stage : {"gcc_phat", "tracker \"pf\""}) {
    Histogram* h = stages->WithLabels({stage}).value();
    for (int i = 0; i < 1000; ++i) h->Observe(latency_s(rng));
  }
  Histogram* sizes =
      registry->AddHistogram("localizer_block_size_bytes", "Block sizes.", {}, ExponentialBuckets(1024, 4, 6))
          .value()
          ->WithLabels({})
          .value();
  sizes->Observe(1024);
  sizes->Observe(1e9);
  // A family that has no series yet.
  ASSERT_TRUE(registry->AddCounter("localizer_errors_total", "Errors.", {"code"}).ok());
}

TEST(Promtool, CheckMetricsAcceptsTheSerializedRegistryWithoutLintWarnings) {
  if (access(kPromtool, X_OK) != 0) {
    GTEST_SKIP() << kPromtool << " not found or not executable (install Debian's `prometheus` "
                 << "package to run this check)";
  }
  Registry registry;
  Fill(&registry);
  const std::string text = registry.Serialize();
  const std::string path = ::testing::TempDir() + "metrics_promtool_test_" + std::to_string(getpid()) + ".prom";
  {
    std::ofstream file(path, std::ios::binary);
    file << text;
    ASSERT_TRUE(file.good()) << "cannot write " << path;
  }
  const CommandResult result = RunCommand(std::string(kPromtool) + " check metrics < '" + path + "'");
  std::remove(path.c_str());
  EXPECT_EQ(result.exit_code, 0) << result.output << "\n--- input ---\n" << text;
  EXPECT_EQ(result.output, "") << "\n--- input ---\n" << text;
}

// The linter is really looking: a counter without the _total suffix is reported.
TEST(Promtool, CheckMetricsReportsALintProblem) {
  if (access(kPromtool, X_OK) != 0) GTEST_SKIP() << kPromtool << " not found";
  Registry registry;
  registry.AddCounter("requests", "Requests.").value()->WithLabels({}).value()->Increment();
  const std::string path = ::testing::TempDir() + "metrics_promtool_lint_" + std::to_string(getpid()) + ".prom";
  {
    std::ofstream file(path, std::ios::binary);
    file << registry.Serialize();
  }
  const CommandResult result = RunCommand(std::string(kPromtool) + " check metrics < '" + path + "'");
  std::remove(path.c_str());
  EXPECT_NE(result.output.find("_total"), std::string::npos) << result.output;
}

}  // namespace
}  // namespace localizer::server::metrics
