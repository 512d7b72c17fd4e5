// localizer-loadgen (clients/loadgen) against an in-process localizer-server on a loopback
// port: a short real-time run accounts for every block and estimate with no error, its
// latencies are finite and ordered, and bad flags exit 2 naming the flag. Also the latency
// histogram's percentiles against exact ones. The binary's path comes from the build
// (LOCALIZER_LOADGEN_BIN); without it those tests skip.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "clients/loadgen/latency_histogram.h"
#include "tests/clients/test_util.h"
#include "tests/server/loopback_server.h"
#include "tests/server/run_shell.h"

namespace localizer::loadgen {
namespace {

using io::testing::TempDir;

#ifdef LOCALIZER_LOADGEN_BIN
#define SKIP_WITHOUT_LOADGEN()
#else
#define LOCALIZER_LOADGEN_BIN ""
#define SKIP_WITHOUT_LOADGEN() GTEST_SKIP() << "LOCALIZER_LOADGEN_BIN not set by the build"
#endif

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// Runs the load generator with `args`; returns its exit code (-1 if it did not exit).
int RunLoadgen(const std::string& args, const std::string& stderr_path) {
  const int status = localizer::testing::RunShell(std::string("'") + LOCALIZER_LOADGEN_BIN + "' " + args + " 2> '" +
                                                  stderr_path + "' > /dev/null");
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

using LoadgenTest = client::LoopbackServerTest;

TEST_F(LoadgenTest, RealtimeRunAccountsForEveryBlockWithOrderedLatencies) {
  SKIP_WITHOUT_LOADGEN();
  TempDir dir;
  const std::string result_path = dir.File("result.json"), err_path = dir.File("stderr.txt");
  const int sessions = 3;
  const int code = RunLoadgen("--target " + target_ + " --sessions " + std::to_string(sessions) +
                                  " --duration 2 --rate realtime --backend cpu --threads 2 --motion one-std --json '" +
                                  result_path + "'",
                              err_path);
  const std::string err = ReadText(err_path);
  ASSERT_EQ(code, 0) << err;
  const nlohmann::json r = nlohmann::json::parse(ReadText(result_path));
  EXPECT_EQ(r["sessions_opened"], sessions);
  EXPECT_EQ(r["motion"], "one-std") << "the sessions above opened with the one-std filter config";
  EXPECT_EQ(r["errors"], 0) << r.dump(2);
  EXPECT_EQ(r["rejected"], 0) << r.dump(2);
  EXPECT_EQ(r["gaps"], 0);
  EXPECT_EQ(r["estimates_unmatched"], 0);
  const int64_t blocks = r["blocks_sent"];
  // 2 s of 4096-sample blocks at 44.1 kHz: 22 per session, on an absolute schedule.
  EXPECT_EQ(blocks, sessions * 22);
  // Frames of 4096 with hop 2048: a session's first block completes one frame, every later
  // block two; every block's estimates arrive before its stream ends.
  EXPECT_EQ(r["estimates_received"].get<int64_t>(), 2 * blocks - sessions);
  const nlohmann::json& latency = r["latency_ms"];
  EXPECT_EQ(latency["count"], r["estimates_received"]);
  const double p50 = latency["p50"], p95 = latency["p95"], p99 = latency["p99"], max = latency["max"];
  for (double v : {p50, p95, p99, max}) EXPECT_TRUE(std::isfinite(v) && v > 0.0) << latency.dump();
  EXPECT_LE(p50, p95);
  EXPECT_LE(p95, p99);
  EXPECT_LE(p99, max);
  EXPECT_LT(max, 2000.0) << "an idle loopback server answers within a block or two";
  EXPECT_GT(r["generator_cpu_us_per_block"].get<double>(), 0.0);
  EXPECT_GT(r["blocks_per_s"].get<double>(), 0.0);
  EXPECT_NE(err.find("live "), std::string::npos) << "a progress line each second: " << err;
}

TEST(LoadgenFlags, ABadFlagExitsTwoNamingTheFlag) {
  SKIP_WITHOUT_LOADGEN();
  TempDir dir;
  const std::string err_path = dir.File("stderr.txt");
  const std::string base = "--target 127.0.0.1:1 --sessions 2 --duration 1 ";
  EXPECT_EQ(RunLoadgen(base + "--rate realtime --hop 0", err_path), 2);
  EXPECT_NE(ReadText(err_path).find("--hop"), std::string::npos) << ReadText(err_path);
  EXPECT_EQ(RunLoadgen(base + "--rate sometimes", err_path), 2);
  EXPECT_NE(ReadText(err_path).find("--rate"), std::string::npos) << ReadText(err_path);
  EXPECT_EQ(RunLoadgen(base + "--rate realtime --motion fast", err_path), 2);
  EXPECT_NE(ReadText(err_path).find("--motion"), std::string::npos) << ReadText(err_path);
  EXPECT_EQ(RunLoadgen(base + "--rate max --sesions 3", err_path), 2);
  EXPECT_NE(ReadText(err_path).find("--sesions"), std::string::npos) << ReadText(err_path);
  EXPECT_EQ(RunLoadgen("--target 127.0.0.1:1 --duration 1 --rate max", err_path), 2);
  EXPECT_NE(ReadText(err_path).find("--sessions"), std::string::npos) << ReadText(err_path);
}

TEST(LatencyHistogram, QuantilesAreTheNearestRankWithinOnePercentAndOrdered) {
  std::mt19937_64 rng(7);
  std::lognormal_distribution<double> draw(std::log(5e-3), 1.0);  // ~5 ms, a long tail
  LatencyHistogram histogram;
  std::vector<double> exact;
  for (int i = 0; i < 20000; ++i) {
    const double v = draw(rng);
    histogram.Add(v);
    exact.push_back(v);
  }
  histogram.Add(std::nan(""));  // ignored
  histogram.Add(-1.0);          // ignored
  std::sort(exact.begin(), exact.end());
  const LatencyCounts counts = histogram.Snapshot();
  ASSERT_EQ(counts.count, exact.size());
  EXPECT_NEAR(counts.max_s, exact.back(), 1e-9);  // kept in whole nanoseconds
  double previous = 0.0;
  for (double q : {0.5, 0.95, 0.99, 1.0}) {
    const double truth = exact[static_cast<size_t>(std::ceil(q * static_cast<double>(exact.size()))) - 1];
    const double got = counts.Quantile(q);
    EXPECT_GE(got, truth - 1e-9) << q;  // never below (up to the max's ns rounding)
    EXPECT_LE(got, truth * 1.01) << q;
    EXPECT_GE(got, previous);
    previous = got;
  }
  // The last second's counts: a difference of snapshots.
  histogram.Add(1.0);
  const LatencyCounts later = histogram.Snapshot().Minus(counts);
  EXPECT_EQ(later.count, 1u);
  EXPECT_NEAR(later.Quantile(0.5), 1.0, 0.01);
}

}  // namespace
}  // namespace localizer::loadgen
