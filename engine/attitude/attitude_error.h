// Attitude error the BROAD benchmark's way (Laidig et al., "BROAD — A Benchmark for Robust
// Inertial Orientation Estimation", Data 2021), so our figures compare with its tables.
//
// For an estimate q_est and the truth q_truth (both body -> world), the error quaternion in
// the world frame is q_err = q_est (x) q_truth^-1 = (w, x, y, z), and
//     total       = 2 acos(|w|)                  the whole rotation angle between them
//     heading     = 2 atan(|z / w|)              its part about the world's Up axis
//     inclination = 2 acos(sqrt(w^2 + z^2))      its part about horizontal axes, blind to
//                                                heading: the fair figure without magnetometer
// (heading and inclination are the angles of the swing-twist split of q_err about Up).
// All in [0, pi]; the sign of q (q and -q are the same rotation) does not matter.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "engine/core/status.h"

namespace localizer::engine {

struct AttitudeError {
  double total_rad = 0.0;
  double heading_rad = 0.0;
  double inclination_rad = 0.0;
};

AttitudeError AttitudeErrorOf(const Eigen::Quaterniond& estimate, const Eigen::Quaterniond& truth);

// RMS of each error over the scored samples.
struct AttitudeScore {
  int64_t count = 0;
  double total_rmse_rad = 0.0;
  double heading_rmse_rad = 0.0;
  double inclination_rmse_rad = 0.0;
};

// Scores estimates[i] against truth[i] where scored[i] is true and the truth is finite (the
// benchmark: movement = 1 and the markers were seen). A non-finite estimate at a scored
// sample counts as an error of pi, so a broken filter cannot score well.
// INVALID_ARGUMENT when the three lengths differ; FAILED_PRECONDITION when no sample is scored.
StatusOr<AttitudeScore> ScoreAttitude(const std::vector<Eigen::Quaterniond>& estimates,
                                      const std::vector<Eigen::Quaterniond>& truth, const std::vector<bool>& scored);

}  // namespace localizer::engine
