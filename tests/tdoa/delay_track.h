// How close an estimator's delays come to the truth on a band-limited source in white noise
// (tdoa_test_signals.h), frame after frame through one estimator: for comparing weightings.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "engine/tdoa/gcc_phat.h"
#include "tests/tdoa/tdoa_test_signals.h"

namespace localizer::engine::testing {

struct DelayTrack {
  double spread = 0.0;  // rms error, samples, over pairs and scored frames
  int lost = 0;         // errors beyond one sample (not in the spread)
};

// `frames` frames of DelayedNoiseFrame (seeds seed, seed + 1, ...) on the tetrahedron with
// fixed delays; the first `warmup` are measured but not scored (estimators that learn).
inline DelayTrack RunDelayedNoiseFrames(const GccOptions& o, const SignalSpec& spec, double snr_db, uint64_t seed,
                                        int frames, int warmup) {
  auto gcc = std::move(*GccPhatEstimator::Create(TetrahedronArray(), o));
  const std::vector<double> delays = {0.0, 3.3, -7.6, 11.45};
  double sum_sq = 0.0;
  int count = 0;
  DelayTrack t;
  Measurement m;
  for (int f = 0; f < frames; ++f) {
    const auto frame = DelayedNoiseFrame(spec, delays, snr_db, seed + f);
    EXPECT_TRUE(gcc->Estimate(frame.data(), spec.frame_samples, 0.0, &m).ok());
    if (f < warmup) continue;
    for (const PairMeasurement& p : m.pairs) {
      const double e = p.delay_s * spec.sample_rate_hz - delays[p.sensor];
      if (std::abs(e) > 1.0) {
        ++t.lost;
        continue;
      }
      sum_sq += e * e;
      ++count;
    }
  }
  t.spread = std::sqrt(sum_sq / std::max(count, 1));
  return t;
}

}  // namespace localizer::engine::testing
