// One-shot localisation: one block of samples -> the TDOA of every pair and a fix.
//
// The whole block is one GCC-PHAT frame (no framing, no tracker, nothing kept between
// calls). The fix is the multilateration of the measured delays (closed form, then
// Levenberg–Marquardt; see engine/array/multilateration.h); its covariance uses the TDOA
// std the fit itself shows, sigma^2 = sum(residual^2) / (pairs - 3), floored at the
// quantisation std of one sample, 1 / (fs sqrt(12)) — with 4 sensors the fit is exact
// and the floor applies.
// Thread-safe (a pure function); costs one FFT plan plus the transforms of one frame.
#pragma once

#include "engine/array/multilateration.h"
#include "engine/core/block.h"
#include "engine/core/measurement.h"
#include "engine/pipeline/session_config.h"

namespace localizer::engine {

struct LocateResult {
  Measurement measurement;  // TDOA, quality and peak SNR per pair
  bool fix_found = false;   // multilateration converged to a finite position
  Fix fix;                  // valid when fix_found
  double tdoa_s = 0.0;      // wall time of the GCC stage, s
};

// Uses config's array, sound speed, reference sensor, sample rate, weighting, phat_beta
// and band; frame_samples and hop_samples are taken from the block (at least 64 samples
// per channel, at most config.max_block_samples). INVALID_ARGUMENT naming the field for a
// bad config or block. A block the fit cannot place is not an error: fix_found = false.
StatusOr<LocateResult> Locate(const AudioSessionConfig& config, const BlockView& block);

}  // namespace localizer::engine
