// The TDOA front end's interface: one multichannel frame in, one Measurement out.
#pragma once

#include <span>

#include "engine/core/measurement.h"
#include "engine/core/status.h"

namespace localizer::engine {

class TdoaEstimator {
 public:
  virtual ~TdoaEstimator() = default;

  // `frame` is channel-major: channel k (= sensor k) occupies
  // frame[k * frame_samples, (k + 1) * frame_samples). `frame_samples` must equal the size
  // the estimator was built for and the channel count the array's. `t_s` is copied into
  // out->t_s. `out` is overwritten; its vectors are reused so a steady stream allocates
  // nothing. Not thread-safe: one estimator per session (they hold FFT buffers).
  virtual Status Estimate(const float* frame, int frame_samples, double t_s, Measurement* out) = 0;

  // The pairs without the reference sensor of the frame last given to Estimate, into
  // out->cross_pairs (Measurement::cross_pairs), for an estimator that measures them; the
  // others (the default) leave out->cross_pairs empty. Measured on demand, not by Estimate,
  // because only acquisition's search reads them: a tracking frame pays nothing.
  virtual Status MeasureCrossPairs(Measurement* out) {
    out->cross_pairs.clear();
    return Status::Ok();
  }

  // The rate (seconds per second) at which each pair's delay is predicted to change during
  // the next frames, one per pair; empty: none (the default). An estimator that compensates
  // (GccPhatEstimator) also measures each such pair with its sensor's channel read along the
  // predicted delay (delay_warp.h), so that a moving source's peak does not smear over the
  // frame, and keeps the reading whose peak is higher; the others (the default) ignore them.
  // Kept until the next call.
  virtual Status SetDelayRates(std::span<const double> rate_per_pair) {
    (void)rate_per_pair;
    return Status::Ok();
  }
};

}  // namespace localizer::engine
