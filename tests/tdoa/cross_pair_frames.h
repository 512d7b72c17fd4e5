// A test frame measured by the CPU GCC-PHAT front end with the pairs without the reference
// (Measurement::cross_pairs), as a tracked frame of a session is: the closure check's and the
// pair fusion's tests read it.
#pragma once

#include <gtest/gtest.h>

#include <vector>

#include "engine/tdoa/gcc_phat.h"
#include "tests/tdoa/tdoa_test_signals.h"

namespace localizer::engine::testing {

// No band is set: PHAT whitens the whole spectrum, as the campaign's sessions do.
inline Measurement MeasureWithCrossPairs(const ArrayGeometry& array, const SignalSpec& spec,
                                         const std::vector<float>& frame, int cross_pairs_max_sensors) {
  GccOptions gcc;
  gcc.frame_samples = spec.frame_samples;
  gcc.sample_rate_hz = spec.sample_rate_hz;
  gcc.keep_gcc = true;
  gcc.cross_pairs_max_sensors = cross_pairs_max_sensors;
  auto estimator = *GccPhatEstimator::Create(array, gcc);
  Measurement m;
  EXPECT_TRUE(estimator->Estimate(frame.data(), spec.frame_samples, 0.0, &m).ok());
  EXPECT_TRUE(estimator->MeasureCrossPairs(&m).ok());
  return m;
}

}  // namespace localizer::engine::testing
