#include "engine/pipeline/framer.h"

#include <algorithm>

namespace localizer::engine {

Framer::Framer(int channel_count, int frame_samples, int hop_samples)
    : channels_(channel_count),
      frame_(frame_samples),
      hop_(hop_samples),
      channels_buffer_(channel_count),
      frame_buffer_(static_cast<size_t>(channel_count) * frame_samples) {}

void Framer::Compact() {
  if (offset_ == 0) return;
  for (auto& buf : channels_buffer_) {
    std::copy(buf.begin() + offset_, buf.begin() + stored_, buf.begin());
  }
  stored_ -= offset_;
  offset_ = 0;
}

void Framer::Append(const BlockView& block) {
  if (offset_ > pending()) Compact();
  const int64_t n = block.samples_per_channel;
  for (int c = 0; c < channels_; ++c) {
    auto& buf = channels_buffer_[c];
    if (static_cast<int64_t>(buf.size()) < stored_ + n) buf.resize(stored_ + n);
    const float* src = block.samples + c * n;
    std::copy(src, src + n, buf.begin() + stored_);
  }
  stored_ += n;
  received_ += n;
}

void Framer::Skip(int64_t samples) {
  received_ += samples;
  offset_ = stored_;
  next_first_ = received_;
}

bool Framer::Next(const float** frame, int64_t* first_sample) {
  if (pending() < frame_) return false;
  for (int c = 0; c < channels_; ++c) {
    const float* src = channels_buffer_[c].data() + offset_;
    std::copy(src, src + frame_, frame_buffer_.begin() + static_cast<int64_t>(c) * frame_);
  }
  *frame = frame_buffer_.data();
  *first_sample = next_first_;
  next_first_ += hop_;
  offset_ += hop_;
  return true;
}

}  // namespace localizer::engine
