// The Track stream's in-band answers besides estimates and track lists: BlockRejected (a
// block, IMU batch or scan refused; the session goes on) and SequenceGap (blocks missing).
#pragma once

#include <cstdint>
#include <string>

#include "engine/core/status.h"
#include "localizer/v1/localizer.pb.h"

namespace localizer::wire {

// `request` is "block", "imu" or "scan"; `reason` the short key (BlockRejected.reason);
// code and message come from `status`.
void RejectionToProto(const char* request, uint64_t sequence, const std::string& reason, const Status& status,
                      v1::BlockRejected* out);

void SequenceGapToProto(uint64_t previous_sequence, uint64_t sequence, uint64_t missing_blocks,
                        uint64_t skipped_samples, v1::SequenceGap* out);

}  // namespace localizer::wire
