// The dispatcher that turns many sessions' calls into batches: plain C++, runs everywhere.
#include "gpu/batch/batch_queue.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <thread>
#include <vector>

namespace localizer::gpu {
namespace {

struct Job {
  int input = 0;
  int output = -1;
  int runs = 0;
};

TEST(BatchQueue, EveryJobRunsExactlyOnceAndGetsItsOwnResult) {
  std::mutex mutex;
  std::vector<size_t> sizes;
  BatchQueue<Job> queue(
      [&](std::span<Job* const> jobs) {
        for (Job* job : jobs) {
          job->output = 3 * job->input + 1;
          ++job->runs;
        }
        std::lock_guard<std::mutex> lock(mutex);
        sizes.push_back(jobs.size());
      },
      std::chrono::milliseconds(2), 16);
  constexpr int kThreads = 32, kJobsPerThread = 50;
  std::vector<std::vector<Job>> jobs(kThreads, std::vector<Job>(kJobsPerThread));
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      for (int j = 0; j < kJobsPerThread; ++j) {
        jobs[t][j].input = t * 1000 + j;
        queue.Submit(&jobs[t][j]);
        // Submit returned: the result is there.
        EXPECT_EQ(jobs[t][j].output, 3 * (t * 1000 + j) + 1);
      }
    });
  }
  for (auto& thread : threads) thread.join();
  for (const auto& per_thread : jobs) {
    for (const Job& job : per_thread) EXPECT_EQ(job.runs, 1);
  }
  size_t total = 0, largest = 0;
  for (size_t size : sizes) {
    total += size;
    largest = std::max(largest, size);
    EXPECT_LE(size, 16u);
  }
  EXPECT_EQ(total, static_cast<size_t>(kThreads * kJobsPerThread));
  // 32 threads submitting within a 2 ms window: batches do form.
  EXPECT_GT(largest, 1u);
  const BatchQueueStats stats = queue.stats();
  EXPECT_EQ(stats.jobs, total);
  EXPECT_EQ(stats.batches, sizes.size());
  EXPECT_EQ(stats.largest_batch, largest);
}

TEST(BatchQueue, AFullBatchLaunchesWithoutWaitingForTheWindow) {
  std::atomic<int> batches{0};
  // A window far longer than the test: only the max_batch rule can launch.
  BatchQueue<Job> queue(
      [&](std::span<Job* const> jobs) {
        EXPECT_EQ(jobs.size(), 4u);
        for (Job* job : jobs) job->output = job->input;
        ++batches;
      },
      std::chrono::seconds(30), 4);
  std::vector<Job> jobs(4);
  std::vector<std::thread> threads;
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < 4; ++i)
    threads.emplace_back([&, i] {
      jobs[i].input = i;
      queue.Submit(&jobs[i]);
    });
  for (auto& thread : threads) thread.join();
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(10));
  EXPECT_EQ(batches.load(), 1);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(jobs[i].output, i);
}

TEST(BatchQueue, ALoneJobWaitsAtMostTheWindow) {
  BatchQueue<Job> queue(
      [](std::span<Job* const> jobs) {
        for (Job* job : jobs) job->output = 7;
      },
      std::chrono::milliseconds(20), 64);
  Job job;
  const auto start = std::chrono::steady_clock::now();
  queue.Submit(&job);
  const auto waited = std::chrono::steady_clock::now() - start;
  EXPECT_EQ(job.output, 7);
  EXPECT_GE(waited, std::chrono::milliseconds(19));  // it did wait for company
  EXPECT_LT(waited, std::chrono::seconds(5));
}

TEST(BatchQueue, WhenEveryProducerWaitsTheBatchRunsWithoutTheWindow) {
  std::atomic<int> batches{0};
  std::atomic<size_t> largest{0};
  // A window far longer than the test: only the producer rule can launch these.
  BatchQueue<Job> queue(
      [&](std::span<Job* const> jobs) {
        for (Job* job : jobs) job->output = job->input;
        largest = std::max(largest.load(), jobs.size());
        ++batches;
      },
      std::chrono::seconds(30), 64);
  const auto start = std::chrono::steady_clock::now();
  queue.AddProducer();  // a lone session: each of its jobs runs at once
  for (int i = 0; i < 20; ++i) {
    Job job;
    job.input = i;
    queue.Submit(&job);
    EXPECT_EQ(job.output, i);
  }
  EXPECT_EQ(batches.load(), 20);
  // Three producers: a batch launches when all three wait, not before.
  queue.AddProducer();
  queue.AddProducer();
  std::vector<Job> jobs(3);
  std::vector<std::thread> threads;
  for (int i = 0; i < 3; ++i)
    threads.emplace_back([&, i] {
      jobs[i].input = 10 + i;
      queue.Submit(&jobs[i]);
    });
  for (auto& thread : threads) thread.join();
  EXPECT_EQ(largest.load(), 3u);
  EXPECT_EQ(batches.load(), 21);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(jobs[i].output, 10 + i);
  // Producers that leave stop being waited for.
  queue.RemoveProducer();
  queue.RemoveProducer();
  Job last;
  last.input = 99;
  queue.Submit(&last);
  EXPECT_EQ(last.output, 99);
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(10));
}

TEST(BatchQueue, ZeroWindowRunsAtOnce) {
  BatchQueue<Job> queue(
      [](std::span<Job* const> jobs) {
        for (Job* job : jobs) job->output = 1;
      },
      std::chrono::nanoseconds(0), 64);
  for (int i = 0; i < 100; ++i) {
    Job job;
    queue.Submit(&job);
    EXPECT_EQ(job.output, 1);
  }
  EXPECT_EQ(queue.stats().jobs, 100u);
}

TEST(BatchQueue, DestructionFinishesQueuedJobs) {
  std::vector<Job> jobs(8);
  std::vector<std::thread> threads;
  {
    BatchQueue<Job> queue(
        [](std::span<Job* const> batch) {
          for (Job* job : batch) job->output = 5;
        },
        std::chrono::seconds(30), 64);
    for (int i = 0; i < 8; ++i) threads.emplace_back([&, i] { queue.Submit(&jobs[i]); });
    // All eight wait in a window far longer than the test; destroy the queue then.
    while (queue.stats().waiting < 8) std::this_thread::yield();
  }
  for (auto& thread : threads) thread.join();
  for (const Job& job : jobs) EXPECT_EQ(job.output, 5);
}

}  // namespace
}  // namespace localizer::gpu
