// One session's GCC-PHAT parameters for the batched GPU stage (gcc_batch.h): its options, the
// transform layout they imply (engine/tdoa/gcc_layout.h, shared with the CPU estimator so the
// two compute the same N, band and lag windows) and the batch key under which its frames can
// share cuFFT executions with other sessions' frames.
//
// Host-side and immutable once created: cheap to copy (O(pairs)), safe to read from any
// thread. Creating one touches no device.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "engine/array/array_geometry.h"
#include "engine/core/status.h"
#include "engine/tdoa/gcc_layout.h"
#include "engine/tdoa/gcc_phat.h"

namespace localizer::gpu {

// Frames whose plans have equal keys go through one batched cuFFT: R2C of fft_size over
// frames * channels rows, C2R over frames * (channels - 1). Everything else (array, band,
// weighting, lag windows, interpolation, keep_gcc) may differ frame by frame.
struct GccBatchKey {
  int frame_samples = 0;  // samples per channel per frame
  int fft_size = 0;       // N
  int channels = 0;       // sensors of the array (pairs = channels - 1)

  bool operator==(const GccBatchKey&) const = default;
  std::string ToString() const;  // "frame_samples=4096 fft_size=5120 channels=4"
};

struct GccBatchKeyHash {
  std::size_t operator()(const GccBatchKey& key) const;
};

class GccPlan {
 public:
  using BatchKey = GccBatchKey;

  // The same validation and errors as engine::GccPhatEstimator::Create: INVALID_ARGUMENT
  // naming the option and value when options.Validate() fails, or when the band holds no FFT
  // bin; and for weighting phat-coherence (learned weights the batch does not keep) and
  // phat-share (weights from every channel before any pair).
  // (measure_fft_plans is ignored: cuFFT plans do not depend on it.)
  static StatusOr<GccPlan> Create(const engine::ArrayGeometry& array, const engine::GccOptions& options);

  const engine::GccOptions& options() const { return options_; }
  const engine::GccLayout& layout() const { return layout_; }
  BatchKey key() const { return {layout_.frame_samples, layout_.fft_size, layout_.channels}; }

  int channels() const { return layout_.channels; }
  int pair_count() const { return layout_.pair_count(); }
  int reference_sensor() const { return reference_sensor_; }
  int sensor_of_pair(int pair) const { return sensor_of_pair_[pair]; }
  // Floats of GCC window a frame returns: sum over pairs of 2 (L_p + K) + 1 with keep_gcc
  // (K = engine::kPeakHalfWidth lags either side for the candidates' refinement), else 0.
  std::size_t gcc_floats() const { return gcc_floats_; }

 private:
  GccPlan() = default;

  engine::GccOptions options_;
  engine::GccLayout layout_;
  int reference_sensor_ = 0;
  std::vector<int> sensor_of_pair_;
  std::size_t gcc_floats_ = 0;
};

}  // namespace localizer::gpu
