// Counter, Gauge and Histogram (server/metrics/metric_types.h): values, monotonicity,
// Prometheus bucket semantics (`le` inclusive, cumulative) and exact totals under
// concurrent updates.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <thread>
#include <vector>

#include "server/metrics/metric_types.h"

namespace localizer::server::metrics {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

TEST(Counter, StartsAtZeroAndAddsIncrements) {
  Counter counter;
  EXPECT_EQ(counter.value(), 0.0);
  counter.Increment();
  counter.Increment(2.5);
  counter.Increment(0.0);
  EXPECT_EQ(counter.value(), 3.5);
}

TEST(Counter, IgnoresNegativeNanAndInfiniteIncrementsSoItNeverDecreases) {
  Counter counter;
  counter.Increment(4.0);
  double previous = counter.value();
  for (const double bad : {-1.0, -1e-300, kNaN, kInf, -kInf}) {
    counter.Increment(bad);
    EXPECT_EQ(counter.value(), previous) << "after Increment(" << bad << ")";
    counter.Increment(1.0);
    EXPECT_GT(counter.value(), previous);
    previous = counter.value();
  }
  EXPECT_EQ(counter.value(), 9.0);
}

TEST(Gauge, SetAddIncrementDecrement) {
  Gauge gauge;
  EXPECT_EQ(gauge.value(), 0.0);
  gauge.Set(10.0);
  gauge.Add(-2.5);
  gauge.Increment();
  gauge.Decrement(4.0);
  EXPECT_EQ(gauge.value(), 4.5);
  gauge.Set(-kInf);
  EXPECT_EQ(gauge.value(), -kInf);
  gauge.Set(kNaN);
  EXPECT_TRUE(std::isnan(gauge.value()));
}

TEST(Histogram, EmptySnapshotHasZeroCountsForEveryBucket) {
  const Histogram histogram({0.1, 1.0});
  const HistogramSnapshot s = histogram.Snapshot();
  EXPECT_EQ(s.upper_bounds, (std::vector<double>{0.1, 1.0}));
  EXPECT_EQ(s.cumulative_counts, (std::vector<uint64_t>{0, 0, 0}));
  EXPECT_EQ(s.count, 0u);
  EXPECT_EQ(s.sum, 0.0);
}

TEST(Histogram, CumulativeBucketsWithInclusiveUpperBounds) {
  Histogram histogram({0.25, 0.5, 1.0});
  // 0.25 and 1.0 lie exactly on bounds: `le` is inclusive, so they count in those buckets.
  for (const double v : {0.125, 0.25, 0.375, 1.0, 4.0, -3.0}) histogram.Observe(v);
  const HistogramSnapshot s = histogram.Snapshot();
  // <= 0.25: -3, 0.125, 0.25 | <= 0.5: + 0.375 | <= 1: + 1.0 | +Inf: + 4.0
  EXPECT_EQ(s.cumulative_counts, (std::vector<uint64_t>{3, 4, 5, 6}));
  EXPECT_EQ(s.count, 6u);
  EXPECT_EQ(s.sum, 0.125 + 0.25 + 0.375 + 1.0 + 4.0 - 3.0);
}

TEST(Histogram, ValueJustAboveABoundGoesToTheNextBucket) {
  Histogram histogram({1.0, 2.0});
  histogram.Observe(std::nextafter(1.0, 2.0));
  histogram.Observe(std::nextafter(2.0, 3.0));
  EXPECT_EQ(histogram.Snapshot().cumulative_counts, (std::vector<uint64_t>{0, 1, 2}));
}

TEST(Histogram, NanIsIgnoredAndInfinitiesLandInTheOuterBuckets) {
  Histogram histogram({1.0});
  histogram.Observe(kNaN);
  EXPECT_EQ(histogram.Snapshot().count, 0u);
  EXPECT_EQ(histogram.Snapshot().sum, 0.0);
  histogram.Observe(-kInf);
  histogram.Observe(kInf);
  const HistogramSnapshot s = histogram.Snapshot();
  EXPECT_EQ(s.cumulative_counts, (std::vector<uint64_t>{1, 2}));
  EXPECT_TRUE(std::isnan(s.sum));  // -Inf + Inf, as any Prometheus client would report
}

TEST(Histogram, WithoutFiniteBoundsEverythingIsInTheInfBucket) {
  Histogram histogram({});
  histogram.Observe(1.0);
  histogram.Observe(2.0);
  const HistogramSnapshot s = histogram.Snapshot();
  EXPECT_EQ(s.cumulative_counts, (std::vector<uint64_t>{2}));
  EXPECT_EQ(s.sum, 3.0);
}

// Concurrency: the totals are exact, not approximately right.
constexpr int kThreads = 4;
constexpr int kPerThread = 100000;

TEST(MetricsConcurrency, CounterTotalIsExactAcrossThreads) {
  Counter counter;
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&counter] {
      for (int i = 0; i < kPerThread; ++i) counter.Increment();
    });
  }
  for (auto& thread : threads) thread.join();
  EXPECT_EQ(counter.value(), static_cast<double>(kThreads) * kPerThread);
}

TEST(MetricsConcurrency, GaugeAddsFromManyThreadsCancelExactly) {
  Gauge gauge;
  gauge.Set(7.0);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&gauge, t] {
      for (int i = 0; i < kPerThread; ++i) {
        if (t % 2 == 0)
          gauge.Increment(2.0);
        else
          gauge.Decrement(2.0);
      }
    });
  }
  for (auto& thread : threads) thread.join();
  EXPECT_EQ(gauge.value(), 7.0);
}

TEST(MetricsConcurrency, HistogramCountsAndSumAreExactAcrossThreads) {
  Histogram histogram({1.0, 2.0});
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&histogram] {
      // 0.5, 1.5, 2.5 in turn: one per bucket; all sums are exact in binary.
      for (int i = 0; i < kPerThread; ++i) histogram.Observe(0.5 + (i % 3));
    });
  }
  // Snapshots taken meanwhile stay cumulative and consistent with their count.
  for (int k = 0; k < 100; ++k) {
    const HistogramSnapshot s = histogram.Snapshot();
    ASSERT_LE(s.cumulative_counts[0], s.cumulative_counts[1]);
    ASSERT_LE(s.cumulative_counts[1], s.cumulative_counts[2]);
    ASSERT_EQ(s.cumulative_counts[2], s.count);
  }
  for (auto& thread : threads) thread.join();
  const HistogramSnapshot s = histogram.Snapshot();
  const uint64_t per_bucket_per_thread[3] = {33334, 33333, 33333};  // i % 3 over 100000
  uint64_t cumulative = 0;
  for (int b = 0; b < 3; ++b) {
    cumulative += kThreads * per_bucket_per_thread[b];
    EXPECT_EQ(s.cumulative_counts[b], cumulative) << "bucket " << b;
  }
  EXPECT_EQ(s.count, static_cast<uint64_t>(kThreads) * kPerThread);
  EXPECT_EQ(s.sum, kThreads * (33334 * 0.5 + 33333 * 1.5 + 33333 * 2.5));
}

}  // namespace
}  // namespace localizer::server::metrics
