#include "server/service/refusal_log.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <thread>
#include <vector>

namespace localizer::server {
namespace {

using std::chrono::milliseconds;

TEST(HttpRefusalLog, TheFirstRefusalIsLoggedThenAtMostOneLineASecondWithTheCountBetween) {
  HttpRefusalLog log;
  const auto t0 = HttpRefusalLog::Clock::time_point{} + std::chrono::hours(1);
  ::testing::internal::CaptureStderr();
  EXPECT_TRUE(log.Note(t0, "/sessions", 401, "missing"));
  EXPECT_FALSE(log.Note(t0 + milliseconds(100), "/sessions", 401, "missing"));
  EXPECT_FALSE(log.Note(t0 + milliseconds(500), "/", 403, "forbidden"));
  EXPECT_FALSE(log.Note(t0 + milliseconds(999), "/", 401, "invalid"));
  EXPECT_TRUE(log.Note(t0 + milliseconds(1000), "/", 401, "invalid"));
  const std::string lines = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(lines.find("event=auth_refused surface=http page=/sessions code=401 reason=missing unlogged=0"),
            std::string::npos)
      << lines;
  EXPECT_NE(lines.find("page=/ code=401 reason=invalid unlogged=3"), std::string::npos) << lines;
  EXPECT_EQ(std::count(lines.begin(), lines.end(), '\n'), 2);
}

TEST(HttpRefusalLog, ConcurrentRefusalsAreAllCountedOnce) {
  // 8 threads x 1000 refusals within one interval: one line, and the next says 7999.
  HttpRefusalLog log(std::chrono::hours(1));
  const auto t0 = HttpRefusalLog::Clock::time_point{} + std::chrono::hours(1);
  ::testing::internal::CaptureStderr();
  std::vector<std::thread> threads;
  std::atomic<int> logged{0};
  for (int t = 0; t < 8; ++t) {
    threads.emplace_back([&] {
      for (int i = 0; i < 1000; ++i) logged += log.Note(t0, "/", 401, "missing") ? 1 : 0;
    });
  }
  for (std::thread& t : threads) t.join();
  EXPECT_EQ(logged.load(), 1);
  EXPECT_TRUE(log.Note(t0 + std::chrono::hours(2), "/", 401, "missing"));
  const std::string lines = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(lines.find("unlogged=7999"), std::string::npos) << lines;
}

}  // namespace
}  // namespace localizer::server
