// A fixed pool of threads that runs submitted tasks in FIFO order.
//
// The server's heavy work (GCC-PHAT and the filter of each session, one-shot locates)
// runs here, never on gRPC's threads, so a slow frame cannot stall the RPC machinery and
// the CPU is shared by at most `threads` frames at a time.
// Thread-safe. Shutdown() (or the destructor) runs every task already submitted, then
// joins; tasks submitted after Shutdown are dropped and Submit returns false.
#pragma once

#include <condition_variable>
#include <deque>
#include <functional>
#include <thread>
#include <vector>

#include "server/sync/mutex.h"

namespace localizer::server {

class WorkerPool final {
 public:
  explicit WorkerPool(int threads);  // threads >= 1
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  bool Submit(std::function<void()> task) EXCLUDES(mutex_);
  void Shutdown() EXCLUDES(mutex_);
  int threads() const { return static_cast<int>(threads_.size()); }

 private:
  void Run() EXCLUDES(mutex_);

  mutable Mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::function<void()>> tasks_ GUARDED_BY(mutex_);
  bool stopping_ GUARDED_BY(mutex_) = false;
  std::vector<std::thread> threads_;
};

}  // namespace localizer::server
