// SampleBlock <-> channel-major samples.
//
// On the wire a block is frame-major interleaved (as in a WAV file), as float32 `samples`
// or 16-bit little-endian `pcm_s16le` (value / 32768). The engine wants channel-major.
// Decoding validates everything the engine would, and says which rule a bad block broke
// (the `reason` keys of BlockRejected and of the rejections metric), so the server can
// answer without touching the session.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "engine/core/block.h"
#include "engine/core/status.h"
#include "localizer/v1/localizer.pb.h"

namespace localizer::wire {

struct BlockLimits {
  int channel_count = 0;  // the array's sensor count
  int64_t max_samples_per_channel = 0;
};

struct DecodedBlock {
  std::vector<float> samples;      // channel-major; reused between calls to save allocations
  engine::BlockView view;          // points into `samples` after a successful decode
  std::vector<float> interleaved;  // scratch for pcm_s16le
};

// On failure returns INVALID_ARGUMENT naming the field and value and sets *reason to one
// of: "channel_count", "empty", "oversize", "bad_samples" (both or neither encoding,
// length not a multiple of channel_count), "non_finite". `out` keeps its capacity.
Status DecodeBlock(const v1::SampleBlock& block, const BlockLimits& limits, DecodedBlock* out, std::string* reason);

// Channel-major samples (`block`) -> a SampleBlock; `pcm16` quantises to pcm_s16le (clipping at
// +-1), else fills `samples`.
void EncodeBlock(const engine::BlockView& block, bool pcm16, v1::SampleBlock* out);

}  // namespace localizer::wire
