// Index maths of a session's device sample ring (gpu/tdoa/sample_ring.h owns the memory):
// each channel keeps the session's most recent samples in a row of `capacity` floats, so a
// frame that overlaps the previous one (a 50 % hop) is read on the device and only the
// samples it adds cross the bus.
//
// The model: a session's stream is the concatenation of every block appended so far; after
// `total` samples per channel the ring holds stream samples [total - capacity, total), stream
// sample t at row index t mod capacity. A frame of F samples starting at stream sample s is
// readable while total - capacity <= s and s + F <= total. Frame f of a framer with hop H
// starts at s = f H.
//
// Shared by the host (which plans each job's descriptors) and the kernels (which follow
// them), like gcc_math.cuh; without nvcc the qualifiers vanish. Every index here is within
// one channel row; a row is at most 2^31 - 1 samples, stream positions are 64-bit (a
// session at 48 kHz passes 2^31 samples after 12 hours). tests/gpu/sample_ring_test.cc
// checks all of it exhaustively for small sizes against a plain std::vector model of the
// stream.
#pragma once

#include <cstdint>

#include "engine/core/host_device.h"

namespace localizer::gpu::ring {

// Row index of the i-th sample after the one at row index `first`: (first + i) mod capacity
// for first in [0, capacity) and i in [0, capacity), without a division (one compare per
// sample in the kernels).
LOCALIZER_HOST_DEVICE inline int32_t Wrap(int32_t first, int32_t i, int32_t capacity) {
  const int32_t index = first + i;
  return index >= capacity ? index - capacity : index;
}

// Row index of stream sample t (t >= 0).
LOCALIZER_HOST_DEVICE inline int32_t RowIndexOf(int64_t t, int32_t capacity) {
  return static_cast<int32_t>(t % capacity);
}

// Row index where frame f (hop H samples) starts.
LOCALIZER_HOST_DEVICE inline int32_t FrameFirst(int64_t frame, int32_t hop_samples, int32_t capacity) {
  return RowIndexOf(frame * hop_samples, capacity);
}

// Whether the frame of `frame_samples` starting at stream sample `start` lies whole in a ring
// of `capacity` after `total` samples.
LOCALIZER_HOST_DEVICE inline bool FrameReadable(int64_t start, int32_t frame_samples, int64_t total, int32_t capacity) {
  return start >= 0 && start >= total - capacity && start + frame_samples <= total;
}

// How a block of `block_samples` is appended after `total` samples: block sample
// source_first + i (i in [0, count)) goes to row index Wrap(write_first, i, capacity). A
// block longer than the ring keeps only its last `capacity` samples (the earlier ones would
// be overwritten within the same append), so count <= capacity and no row index is written
// twice; first_run of them go before the wrap, count - first_run after it (at index 0).
struct AppendPlan {
  int32_t source_first = 0;
  int32_t write_first = 0;
  int32_t count = 0;
  int32_t first_run = 0;
};

LOCALIZER_HOST_DEVICE inline AppendPlan PlanAppend(int64_t total, int32_t block_samples, int32_t capacity) {
  AppendPlan p;
  const int32_t kept = block_samples < capacity ? block_samples : capacity;
  p.source_first = block_samples - kept;
  p.count = kept;
  p.write_first = RowIndexOf(total + p.source_first, capacity);
  const int32_t room = capacity - p.write_first;
  p.first_run = kept < room ? kept : room;
  return p;
}

// Ring capacity (samples per channel) for reading, after each append, every frame that the
// appended block completed (frame f is completed by a block that brings stream sample
// f H + F - 1), with frames of F samples every H samples starting at stream sample 0:
//   blocks of any sizes up to max_block:  F + max_block - 1. The earliest frame a block of n
//     completes may start n + F - 1 samples before the block's end, and with blocks of mixed
//     sizes every alignment of the frame grid against the block's end occurs.
//   blocks of exactly `block` samples:    F + n - 1 - ((F + n - 1) mod gcd(n, H)). The block
//     ends are multiples of n, so the frame grid meets them only at multiples of gcd(n, H).
//     E.g. H = n = F / 2 gives F: a 50 % hop needs no more than one frame.
// Reading only the newest frame after each append (what GpuTdoaEstimator does) needs F.
// Both are tight (the test finds a stream that needs every sample of them).
LOCALIZER_HOST_DEVICE inline int64_t CapacityForAnyBlocks(int32_t frame_samples, int32_t max_block_samples) {
  return static_cast<int64_t>(frame_samples) + max_block_samples - 1;
}

LOCALIZER_HOST_DEVICE inline int32_t Gcd(int32_t a, int32_t b) {
  while (b != 0) {
    const int32_t r = a % b;
    a = b;
    b = r;
  }
  return a;
}

LOCALIZER_HOST_DEVICE inline int64_t CapacityForFixedBlocks(int32_t frame_samples, int32_t hop_samples,
                                                            int32_t block_samples) {
  const int64_t span = static_cast<int64_t>(frame_samples) + block_samples - 1;
  return span - span % Gcd(block_samples, hop_samples);
}

// One GCC job's ring work: append the last `new_samples` of each channel of the job's host
// frame (F samples per channel), then read the frame (the stream's newest F samples) from
// the ring. new_samples = F re-sends the whole frame (a fresh or invalidated ring); fewer
// needs the ring to hold the rest, i.e. total >= F - new_samples.
struct RingJobPlan {
  AppendPlan append;        // source indices are within the host frame's channel row
  int32_t frame_first = 0;  // row index of the frame's first sample after the append
};

LOCALIZER_HOST_DEVICE inline RingJobPlan PlanRingJob(int64_t total, int32_t capacity, int32_t frame_samples,
                                                     int32_t new_samples) {
  RingJobPlan p;
  p.append = PlanAppend(total, new_samples, capacity);
  p.append.source_first += frame_samples - new_samples;  // the block is the frame's tail
  p.frame_first = RowIndexOf(total + new_samples - frame_samples, capacity);
  return p;
}

}  // namespace localizer::gpu::ring
