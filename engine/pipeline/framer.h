// Cuts an arbitrary stream of channel-major blocks into overlapping frames.
//
// Frame f covers samples [f * hop, f * hop + frame) of every channel. Samples are held in one
// channel-major buffer with a read offset; the buffer is compacted only when the consumed
// part exceeds what is still pending, so each sample is moved O(1) times on average and a
// steady stream of equal blocks stops allocating after its first blocks.
#pragma once

#include <cstdint>
#include <vector>

#include "engine/core/block.h"

namespace localizer::engine {

class Framer {
 public:
  Framer(int channel_count, int frame_samples, int hop_samples);

  // Appends a block whose channel count was validated by the caller.
  void Append(const BlockView& block);
  // When a whole frame is buffered: copies it (channel-major) into an internal buffer,
  // points `*frame` at it, sets `*first_sample` (index of its first sample in the stream),
  // advances by one hop and returns true. `*frame` stays valid until the next call.
  bool Next(const float** frame, int64_t* first_sample);

  // The stream lost `samples` per channel here: samples buffered so far are dropped (a
  // frame never spans the gap) and the next frame starts at the first sample appended
  // after the gap, whose stream index counts the lost ones.
  void Skip(int64_t samples);

 private:
  int64_t pending() const { return stored_ - offset_; }
  void Compact();

  int channels_, frame_, hop_;
  std::vector<std::vector<float>> channels_buffer_;  // per channel, [0, stored_)
  int64_t stored_ = 0;                               // samples per channel held in the buffers
  int64_t offset_ = 0;                               // start of the next frame within the buffers
  int64_t next_first_ = 0;                           // stream index of the next frame's first sample
  int64_t received_ = 0;
  std::vector<float> frame_buffer_;
};

}  // namespace localizer::engine
