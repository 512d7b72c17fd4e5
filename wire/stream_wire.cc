#include "wire/stream_wire.h"

namespace localizer::wire {

void RejectionToProto(const char* request, uint64_t sequence, const std::string& reason, const Status& status,
                      v1::BlockRejected* out) {
  out->set_request(request);
  out->set_sequence(sequence);
  out->set_code(StatusCodeName(status.code()));
  out->set_message(status.message());
  out->set_reason(reason);
}

void SequenceGapToProto(uint64_t previous_sequence, uint64_t sequence, uint64_t missing_blocks,
                        uint64_t skipped_samples, v1::SequenceGap* out) {
  out->set_previous_sequence(previous_sequence);
  out->set_sequence(sequence);
  out->set_missing_blocks(missing_blocks);
  out->set_skipped_samples(skipped_samples);
}

}  // namespace localizer::wire
