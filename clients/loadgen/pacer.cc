#include "clients/loadgen/pacer.h"

#include <algorithm>
#include <chrono>
#include <functional>
#include <queue>
#include <utility>

namespace localizer::loadgen {

namespace {

constexpr int64_t kMaxSleepNs = 50'000'000;  // see a stop within 50 ms

struct Wake {
  int64_t due_ns;
  LoadSession* session;
  bool open;  // the first wake-up: start the stream
  bool operator>(const Wake& other) const { return due_ns > other.due_ns; }
};

}  // namespace

Pacer::Pacer(std::vector<LoadSession*> sessions, const std::atomic<bool>* stop)
    : sessions_(std::move(sessions)), stop_(stop) {}

Pacer::~Pacer() { Join(); }

void Pacer::Start() {
  thread_ = std::thread([this] { Run(); });
}

void Pacer::Join() {
  if (thread_.joinable()) thread_.join();
}

void Pacer::Run() {
  std::priority_queue<Wake, std::vector<Wake>, std::greater<Wake>> heap;
  for (LoadSession* s : sessions_) heap.push({s->start_ns(), s, true});
  bool stop_seen = false;
  while (!heap.empty()) {
    if (!stop_seen && stop_->load(std::memory_order_relaxed)) {
      // Stopped: sessions not yet started never will be; the others half-close now.
      stop_seen = true;
      std::vector<Wake> rest;
      for (; !heap.empty(); heap.pop()) rest.push_back(heap.top());
      for (const Wake& w : rest) {
        if (w.open) {
          w.session->Skip();
        } else {
          heap.push({NowNs(), w.session, false});
        }
      }
      continue;
    }
    const int64_t now_ns = NowNs();
    const Wake next = heap.top();
    if (next.due_ns > now_ns) {
      std::this_thread::sleep_for(std::chrono::nanoseconds(std::min(next.due_ns - now_ns, kMaxSleepNs)));
      continue;
    }
    heap.pop();
    if (next.open) next.session->Open();
    const int64_t again_ns = next.session->Tick(NowNs());
    if (again_ns >= 0) heap.push({again_ns, next.session, false});
  }
}

}  // namespace localizer::loadgen
