// Position error of a track against the simulator's truth.
//
// For every initialised estimate whose t_s lies within [first truth t_s, last truth t_s],
// the truth position is interpolated linearly in time at t_s (both tables use the same
// instant convention: reception time at the reference sensor) and the 3-D Euclidean error
// |p_est - p_truth| is taken. Estimates outside the truth span are skipped rather than
// extrapolated; uninitialised ones carry no position. An initialised estimate with a
// non-finite position counts as an infinite error, so a broken track cannot score well.
//
// Statistics over the n errors, sorted ascending e_(1) <= ... <= e_(n):
//   rmse   = sqrt(mean e^2)
//   median = e_((n+1)/2) for odd n, the mean of the two middle values for even n
//   p95    = e_(ceil(0.95 n))   (nearest rank: the smallest error >= 95 % of all errors)
//   max    = e_(n)
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "clients/io/csv_io.h"
#include "engine/core/status.h"
#include "engine/sim/simulator.h"

namespace localizer::io {

struct ScoreResult {
  int64_t count = 0;  // estimates scored
  double rmse_m = 0.0;
  double median_m = 0.0;
  double p95_m = 0.0;
  double max_m = 0.0;
};

// INVALID_ARGUMENT when truth is empty or not ordered by t_s; FAILED_PRECONDITION when no
// estimate could be scored (none initialised inside the truth span).
StatusOr<ScoreResult> Score(const std::vector<engine::TruthRow>& truth, const std::vector<EstimateRow>& estimates);

// "n=31, rmse_m=0.1234, median_m=0.1, p95_m=0.3, max_m=0.41"
std::string FormatScore(const ScoreResult& score);

}  // namespace localizer::io
