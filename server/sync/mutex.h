// An annotated mutex and its scoped lock: std::mutex and std::lock_guard as the clang
// thread-safety analysis can see them (thread_annotations.h). Same cost as std::mutex.
//
//   mutable Mutex mutex_;
//   int count_ GUARDED_BY(mutex_) = 0;
//   void Add() EXCLUDES(mutex_) { MutexLock lock(&mutex_); ++count_; }
//
// Waiting on a condition variable: hold the lock and call mutex_.Wait(&cv) in a loop over
// the condition (the analysis does not follow predicates passed as lambdas).
#pragma once

#include <chrono>
#include <condition_variable>
#include <mutex>

#include "server/sync/thread_annotations.h"

namespace localizer::server {

class CAPABILITY("mutex") Mutex final {
 public:
  Mutex() = default;
  Mutex(const Mutex&) = delete;
  Mutex& operator=(const Mutex&) = delete;

  void Lock() ACQUIRE() { mutex_.lock(); }
  void Unlock() RELEASE() { mutex_.unlock(); }

  // Blocks until `cv` is notified (or wakes spuriously); the mutex is released meanwhile
  // and held again on return.
  void Wait(std::condition_variable* cv) REQUIRES(this) {
    std::unique_lock<std::mutex> lock(mutex_, std::adopt_lock);
    cv->wait(lock);
    lock.release();  // still held: the caller's MutexLock releases it
  }
  // As Wait, for at most `timeout`.
  template <class Rep, class Period>
  void WaitFor(std::condition_variable* cv, std::chrono::duration<Rep, Period> timeout) REQUIRES(this) {
    std::unique_lock<std::mutex> lock(mutex_, std::adopt_lock);
    cv->wait_for(lock, timeout);
    lock.release();
  }

 private:
  std::mutex mutex_;
};

// Holds `mutex` for its scope.
class SCOPED_CAPABILITY MutexLock final {
 public:
  explicit MutexLock(Mutex* mutex) ACQUIRE(mutex) : mutex_(mutex) { mutex_->Lock(); }
  ~MutexLock() RELEASE() { mutex_->Unlock(); }
  MutexLock(const MutexLock&) = delete;
  MutexLock& operator=(const MutexLock&) = delete;

 private:
  Mutex* const mutex_;
};

}  // namespace localizer::server
