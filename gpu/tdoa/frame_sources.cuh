// Where the GCC pack kernel finds each frame's samples and what the ring append kernel
// copies where (gcc_kernels.h holds the descriptors): the descriptors a job gets, and the
// element addresses the kernels compute from them. Host and device share these functions
// (like gcc_math.cuh), so tests/gpu/gcc_ring_plan_test.cc can run a batch's appends and
// packs on host memory exactly as the kernels index them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "engine/core/host_device.h"
#include "gpu/tdoa/gcc_kernels.h"
#include "gpu/tdoa/sample_ring.cuh"

namespace localizer::gpu {

// A frame read where it lies: channel-major, rows of frame_samples, never wrapping.
LOCALIZER_HOST_DEVICE inline GccFrameSource WholeFrameSource(const float* frame, int32_t frame_samples) {
  return {frame, frame_samples, 0};
}

// A ring job (GccJob::ring): append the last `new_samples` of each row of the host frame to
// a ring of `capacity` after `total` samples, then read the frame from the ring.
struct RingJobDescriptors {
  GccRingAppend append;
  GccFrameSource source;
};

LOCALIZER_HOST_DEVICE inline RingJobDescriptors DescribeRingJob(const float* host_frame, float* ring_samples,
                                                                int32_t capacity, int64_t total, int32_t frame_samples,
                                                                int32_t new_samples) {
  const ring::RingJobPlan p = ring::PlanRingJob(total, capacity, frame_samples, new_samples);
  RingJobDescriptors d;
  d.append = {host_frame, ring_samples,         frame_samples, p.append.source_first,
              capacity,   p.append.write_first, p.append.count};
  d.source = {ring_samples, capacity, p.frame_first};
  return d;
}

// What a job's device reads come from when its frame is not in pinned memory: the batch
// copies into its pinned staging only what the device will read, each row's last
// `new_samples` (the whole frame for a job without a ring). Host only.
inline void StageNewSamples(const float* frame, float* staged, int channels, int32_t frame_samples,
                            int32_t new_samples) {
  for (int c = 0; c < channels; ++c) {
    const std::size_t tail = static_cast<std::size_t>(c) * frame_samples + (frame_samples - new_samples);
    std::memcpy(staged + tail, frame + tail, sizeof(float) * new_samples);
  }
}

// Sample i of channel c of a frame (i < frame_samples).
LOCALIZER_HOST_DEVICE inline const float* FrameSample(const GccFrameSource& s, int channel, int i) {
  return s.samples + static_cast<std::size_t>(channel) * s.row_samples + ring::Wrap(s.first, i, s.row_samples);
}

// The i-th sample an append copies in channel c (i < count): from where, to where.
LOCALIZER_HOST_DEVICE inline const float* AppendFrom(const GccRingAppend& a, int channel, int i) {
  return a.source + static_cast<std::size_t>(channel) * a.source_row_samples + a.source_first + i;
}
LOCALIZER_HOST_DEVICE inline float* AppendTo(const GccRingAppend& a, int channel, int i) {
  return a.ring + static_cast<std::size_t>(channel) * a.capacity + ring::Wrap(a.write_first, i, a.capacity);
}

}  // namespace localizer::gpu
