// A session's recent samples kept on the device, so that frames overlapping the previous
// ones (a 50 % hop) need only their new samples brought over the bus: each GCC job that
// names a ring appends its frame's new samples to it and the pack kernel reads the frame
// from it (gcc_batch.h, GccJob::ring). The index maths, shared by host and kernels, are in
// sample_ring.cuh; this class owns the memory and the host's account of what it holds.
//
// Layout: `channels` rows of `capacity` floats in one device allocation; the stream's sample
// t of channel c at c * capacity + t mod capacity. total() counts the samples per channel
// appended since the ring was last (re)started; a ring that is not valid() holds nothing
// usable (fresh, or a batch failed on the device while appending to it) and its next job
// must bring a whole frame. GccBatch::Run advances or invalidates it; nothing else should.
//
// Memory: channels * capacity * 4 bytes of device memory (a 4-channel ring of one 4096-sample
// frame: 64 KiB; 5000 sessions: 320 MiB). Not thread-safe; a session's ring is touched only
// by the batch that runs its job while the session waits.
#pragma once

#include <cstdint>

#include "engine/core/status.h"
#include "gpu/core/device_buffer.h"

namespace localizer::gpu {

class SampleRing {
 public:
  // INVALID_ARGUMENT for channels < 1 or capacity < 1; RESOURCE_EXHAUSTED when the device's
  // memory ran out. The ring starts invalid.
  static StatusOr<SampleRing> Create(int channels, int capacity);
  SampleRing() = default;

  float* data() const { return memory_.data(); }
  int channels() const { return channels_; }
  int capacity() const { return capacity_; }
  bool valid() const { return valid_; }
  int64_t total() const { return valid_ ? total_ : 0; }

  // The batch's account after its launch completed: `samples` more per channel (a ring that
  // was invalid restarts with them) / the contents are unknown.
  void Advance(int samples);
  void Invalidate() { valid_ = false; }

 private:
  SampleRing(DeviceBuffer<float> memory, int channels, int capacity)
      : memory_(std::move(memory)), channels_(channels), capacity_(capacity) {}
  DeviceBuffer<float> memory_;
  int channels_ = 0;
  int capacity_ = 0;
  int64_t total_ = 0;
  bool valid_ = false;
};

}  // namespace localizer::gpu
