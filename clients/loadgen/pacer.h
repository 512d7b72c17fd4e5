// A pacing thread: starts its sessions at their start times and wakes each one when its
// next block is due (realtime), when it must half-close, or when its deadline passes.
//
// Wake-ups come from a min-heap of (time, session), so one thread paces hundreds of
// sessions at a cost of O(log n) per block; it sleeps in between, at most 50 ms at a time
// so that a stop (Ctrl-C) is seen promptly. At max rate the sessions chain their own writes
// on gRPC's threads and the pacer only starts them and watches their deadlines.
#pragma once

#include <atomic>
#include <thread>
#include <vector>

#include "clients/loadgen/load_session.h"

namespace localizer::loadgen {

class Pacer {
 public:
  // `sessions` (not owned) must outlive Join(); `stop` is the run's stop flag.
  Pacer(std::vector<LoadSession*> sessions, const std::atomic<bool>* stop);
  ~Pacer();
  Pacer(const Pacer&) = delete;
  Pacer& operator=(const Pacer&) = delete;

  void Start();
  // Returns once every session has been started (or skipped) and handed back by Tick.
  void Join();

 private:
  void Run();

  std::vector<LoadSession*> sessions_;
  const std::atomic<bool>* stop_;
  std::thread thread_;
};

}  // namespace localizer::loadgen
