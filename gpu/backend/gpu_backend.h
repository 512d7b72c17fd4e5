// The CUDA backend of the engine: registers a BackendProvider (engine/pipeline/backend.h)
// whose estimators and trackers run on device 0.
//
// What runs where:
//   - GCC-PHAT (GpuTdoaEstimator): each session's frame is queued; a dispatcher thread
//     collects frames from many sessions (for at most batch_window_s, or until
//     max_batch_frames wait), and runs them as one launch sequence per frame shape
//     (gpu/tdoa/gcc_batch.h: one batched cuFFT over every channel of every frame). Each
//     session's newest frame stays on the device (gpu/tdoa/sample_ring.h), so a frame that
//     overlaps the previous one brings only its new samples over the bus.
//   - Particle filter (GpuParticleFilter): particles of every session live in one device
//     bank (gpu/filters/particle_bank.h) between frames; a second dispatcher collects
//     sessions' updates the same way and steps them all in one launch sequence; sessions
//     that start or restart together initialise in one launch. Only the TDOAs/GCC windows
//     go in and the estimate comes out per frame.
// A session's thread blocks while its frame is in a batch, so a server using this backend
// wants more worker threads than cores (localizer-server sizes them).
// Results do not depend on which other sessions share a batch: every reduction is per
// session and in a fixed order, and random numbers are counter-based (Philox) keyed by the
// session's seed and step.
//
// Without a device (or in a build without CUDA: gpu_backend_stub.cc) the provider is still
// registered and reports why, so "gpu" sessions fail at open with FAILED_PRECONDITION
// naming the reason and "auto" sessions run on the CPU.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "engine/core/status.h"

namespace localizer::gpu {

struct GpuBackendOptions {
  double batch_window_s = 0.001;     // longest a queued frame waits for others, in [0, 1]
  int max_batch_frames = 1024;       // a batch launches as soon as this many frames wait, >= 1
  std::size_t bank_limit_bytes = 0;  // device memory the particle bank may use; 0: 3/4 of the
                                     // memory free when the first GPU session opens

  Status Validate() const;  // INVALID_ARGUMENT naming the field
};

// Installs the GPU provider (engine::SetGpuProvider). Call once at start-up, before
// sessions open; later calls replace the provider (sessions already open keep theirs).
Status RegisterGpuBackend(const GpuBackendOptions& options = {});

// True when this binary was built with the CUDA backend (false: the stub).
bool BuiltWithCuda();

// The device's name ("" without one) for logs and metrics.
std::string DeviceName();

// What the dispatchers have batched so far (zeros before the first GPU session), for the
// localizer_gpu_batches_total / localizer_gpu_batched_total metrics: the ratio is the mean
// batch size.
struct GpuBatchCounts {
  uint64_t gcc_batches = 0;
  uint64_t gcc_frames = 0;
  uint64_t filter_batches = 0;
  uint64_t filter_steps = 0;
};
GpuBatchCounts BatchCounts();

}  // namespace localizer::gpu
