// Collects work items submitted by many threads into batches run by one dispatcher thread.
//
// A session's thread calls Submit(&job) and blocks; the dispatcher takes the first waiting
// job, keeps collecting until `max_batch` jobs wait or `window` has passed since that first
// job arrived, then hands all of them (at most max_batch) to `run` in arrival order, and
// wakes their submitters. With window 0 it still batches whatever arrived while the
// previous batch ran (adaptive batching: no added wait when idle).
// Producers: a submitter that will keep submitting one job at a time (a session) may
// register with AddProducer. When every registered producer has a job waiting, no further
// job can join the batch, so it runs at once instead of waiting out the window: a lone
// session pays no window, and sessions that arrive together do not wait for nobody.
// Unregistered submitters are served too; for them only the window and max_batch count.
// Why: one 4-channel frame or one 4096-particle update is far too small to fill a GPU; a
// launch sequence over a thousand sessions' work costs about what one session's does.
//
// `run` must give every job its result (the queue does not look inside jobs) and must not
// throw. Jobs are owned by their submitters and must stay alive until Submit returns.
// The destructor finishes the jobs already queued, then stops the thread; Submit after
// destruction has begun is a programming error.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <semaphore>
#include <span>
#include <thread>
#include <vector>

namespace localizer::gpu {

// What a queue has done, for metrics and benchmarks.
struct BatchQueueStats {
  uint64_t batches = 0;
  uint64_t jobs = 0;
  uint64_t largest_batch = 0;
  uint64_t waiting = 0;  // jobs queued and not yet taken, now
};

template <typename Job>
class BatchQueue {
 public:
  using RunBatch = std::function<void(std::span<Job* const>)>;

  BatchQueue(RunBatch run, std::chrono::nanoseconds window, int max_batch)
      : run_(std::move(run)), window_(window), max_batch_(max_batch < 1 ? 1 : max_batch), thread_([this] { Loop(); }) {}

  ~BatchQueue() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopping_ = true;
    }
    arrived_.notify_all();
    thread_.join();
  }
  BatchQueue(const BatchQueue&) = delete;
  BatchQueue& operator=(const BatchQueue&) = delete;

  // Blocks until `run` has processed `job`. Each submitter waits on its own semaphore, so a
  // finished batch wakes its own submitters only (with thousands of sessions blocked, one
  // shared condition variable woke every one of them for every batch).
  void Submit(Job* job) {
    std::binary_semaphore done(0);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (pending_.empty()) first_arrival_ = std::chrono::steady_clock::now();
      pending_.push_back({job, &done});
    }
    arrived_.notify_one();
    done.acquire();
  }

  // One more / one fewer registered producer (see the top of the file). RemoveProducer after
  // the producer's last Submit returned.
  void AddProducer() {
    std::lock_guard<std::mutex> lock(mutex_);
    ++producers_;
  }
  void RemoveProducer() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (producers_ > 0) --producers_;
    }
    arrived_.notify_one();  // the jobs waiting may now be every producer's
  }

  BatchQueueStats stats() const {
    std::lock_guard<std::mutex> lock(mutex_);
    BatchQueueStats now = stats_;
    now.waiting = pending_.size();
    return now;
  }

 private:
  struct Entry {
    Job* job;
    std::binary_semaphore* done;  // released once `run` has processed job
  };

  void Loop() {
    std::vector<Entry> taken;
    std::vector<Job*> batch;
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      arrived_.wait(lock, [&] { return stopping_ || !pending_.empty(); });
      if (pending_.empty()) return;  // stopping, nothing left
      const auto deadline = first_arrival_ + window_;
      arrived_.wait_until(lock, deadline, [&] {
        const auto waiting = static_cast<int64_t>(pending_.size());
        return stopping_ || waiting >= max_batch_ || (producers_ > 0 && waiting >= producers_);
      });
      const size_t take = std::min(pending_.size(), static_cast<size_t>(max_batch_));
      taken.assign(pending_.begin(), pending_.begin() + static_cast<std::ptrdiff_t>(take));
      pending_.erase(pending_.begin(), pending_.begin() + static_cast<std::ptrdiff_t>(take));
      if (!pending_.empty()) first_arrival_ = std::chrono::steady_clock::now();
      ++stats_.batches;
      stats_.jobs += take;
      stats_.largest_batch = std::max<uint64_t>(stats_.largest_batch, take);
      lock.unlock();
      batch.clear();
      for (const Entry& e : taken) batch.push_back(e.job);
      run_(std::span<Job* const>(batch.data(), batch.size()));
      // The submitter may return and free its semaphore as soon as it is released.
      for (const Entry& e : taken) e.done->release();
      lock.lock();
    }
  }

  RunBatch run_;
  const std::chrono::nanoseconds window_;
  const int max_batch_;
  mutable std::mutex mutex_;
  std::condition_variable arrived_;
  std::vector<Entry> pending_;  // arrival order
  std::chrono::steady_clock::time_point first_arrival_;
  int64_t producers_ = 0;
  bool stopping_ = false;
  BatchQueueStats stats_;
  std::thread thread_;  // last: starts after every other member is constructed
};

}  // namespace localizer::gpu
