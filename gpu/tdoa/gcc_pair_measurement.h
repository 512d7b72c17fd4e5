// The host's share of the batched GCC (gcc_batch.h): one (frame, pair)'s kernel results made
// into the engine::PairMeasurement that GccPhatEstimator would give, by the CPU's own
// functions for delay_sigma_s and the candidate peaks (engine/tdoa/delay_statistics.h).
// Picking the candidates scans and sorts the window's extrema (microseconds per pair of a
// wide window), so it is a separate step: a session runs it on its own thread
// (GccJob::tails), not on the thread that runs the batch for everyone.
#pragma once

#include <span>
#include <vector>

#include "engine/core/measurement.h"
#include "engine/tdoa/delay_statistics.h"
#include "gpu/tdoa/gcc_kernels.h"
#include "gpu/tdoa/gcc_plan.h"

namespace localizer::gpu {

// What a pair's candidates are picked from: the spread the device's moments give, the main
// peak's index in the searched window and R at lags -(L + K)..L + K (K =
// engine::kPeakHalfWidth).
struct GccPairTail {
  engine::DelaySpread spread;
  int peak_index = 0;
  std::vector<float> padded;  // empty: nothing measured, or keep_gcc off
};

// Pair `pair` of `plan` from its kernel result and kept window (R at lags -(L + K)..L + K;
// null with keep_gcc off): every field of *out as GccPhatEstimator fills it, but candidates
// hold the main peak alone (none when nothing was measured), and *tail what
// FinishCandidates needs for the others.
void FillPairMeasurement(const GccPlan& plan, int pair, const GccPairResult& result, const float* window,
                         GccPairTail* tail, engine::PairMeasurement* out);

// Picks out->pairs[p]'s other candidates from tails[p], as GccPhatEstimator does (`scratch`
// is reused between calls).
void FinishCandidates(const GccPlan& plan, std::span<const GccPairTail> tails, engine::Measurement* out,
                      std::vector<engine::WindowExtremum>* scratch);

}  // namespace localizer::gpu
