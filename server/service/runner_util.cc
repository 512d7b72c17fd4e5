#include "server/service/runner_util.h"

#include <time.h>

namespace localizer::server {

double ThreadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

Rejection NotMoving(uint64_t batch_sequence) {
  return {RequestKind::kImu, batch_sequence, "not_moving",
          FailedPrecondition("imu batch for a session whose array is fixed in the world (open it with "
                             "SessionConfig.platform)")};
}

}  // namespace localizer::server
