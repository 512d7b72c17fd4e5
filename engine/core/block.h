// A block of samples as the engine takes it: a non-owning, channel-major view.
#pragma once

#include <cstdint>

namespace localizer::engine {

// `samples[c * samples_per_channel + n]` is sample n of channel c (channel c = sensor c).
// Values are float32 in any consistent unit (pressure or full scale); only ratios matter.
// The caller keeps the memory alive for the duration of the call it passes the view to.
struct BlockView {
  uint64_t sequence = 0;            // strictly increasing within a session
  int channel_count = 0;            // must equal the array's sensor count
  int64_t samples_per_channel = 0;  // > 0
  const float* samples = nullptr;   // channel_count * samples_per_channel values
};

}  // namespace localizer::engine
