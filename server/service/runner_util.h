// Small helpers the session runners share: clocks, null-safe metric updates, the refusals
// more than one runner gives.
#pragma once

#include <cstdint>

#include "server/metrics/metric_types.h"
#include "server/service/inbox.h"

namespace localizer::server {

inline double Seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

// CPU time of the calling thread: what the engine really costs, preemption excluded.
double ThreadCpuSeconds();

inline void Observe(metrics::Histogram* h, double v) {
  if (h != nullptr) h->Observe(v);
}
inline void Bump(metrics::Counter* c, double v = 1.0) {
  if (c != nullptr) c->Increment(v);
}

// An IMU batch for a session whose array is fixed in the world: reason "not_moving".
Rejection NotMoving(uint64_t batch_sequence);

}  // namespace localizer::server
