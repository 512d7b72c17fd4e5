#include "engine/attitude/attitude_error.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace localizer::engine {

AttitudeError AttitudeErrorOf(const Eigen::Quaterniond& estimate, const Eigen::Quaterniond& truth) {
  const Eigen::Quaterniond e = estimate.normalized() * truth.normalized().conjugate();
  const double w = std::abs(e.w()), z = std::abs(e.z());
  AttitudeError error;
  error.total_rad = 2.0 * std::acos(std::min(1.0, w));
  // atan2 instead of atan(z / w): the same for w > 0, and pi rather than a division by 0.
  error.heading_rad = 2.0 * std::atan2(z, w);
  error.inclination_rad = 2.0 * std::acos(std::min(1.0, std::sqrt(w * w + z * z)));
  return error;
}

StatusOr<AttitudeScore> ScoreAttitude(const std::vector<Eigen::Quaterniond>& estimates,
                                      const std::vector<Eigen::Quaterniond>& truth, const std::vector<bool>& scored) {
  if (estimates.size() != truth.size() || scored.size() != truth.size()) {
    return InvalidArgument("attitude score: " + std::to_string(estimates.size()) + " estimates, " +
                           std::to_string(truth.size()) + " truth samples and " + std::to_string(scored.size()) +
                           " flags: the lengths must match");
  }
  AttitudeScore score;
  double total = 0.0, heading = 0.0, inclination = 0.0;
  for (size_t i = 0; i < truth.size(); ++i) {
    if (!scored[i] || !truth[i].coeffs().allFinite()) continue;
    ++score.count;
    if (!estimates[i].coeffs().allFinite() || estimates[i].norm() == 0.0) {
      total += M_PI * M_PI;
      heading += M_PI * M_PI;
      inclination += M_PI * M_PI;
      continue;
    }
    const AttitudeError e = AttitudeErrorOf(estimates[i], truth[i]);
    total += e.total_rad * e.total_rad;
    heading += e.heading_rad * e.heading_rad;
    inclination += e.inclination_rad * e.inclination_rad;
  }
  if (score.count == 0) {
    return FailedPrecondition("attitude score: no sample is scored (movement = 1 with finite truth)");
  }
  score.total_rmse_rad = std::sqrt(total / static_cast<double>(score.count));
  score.heading_rmse_rad = std::sqrt(heading / static_cast<double>(score.count));
  score.inclination_rmse_rad = std::sqrt(inclination / static_cast<double>(score.count));
  return score;
}

}  // namespace localizer::engine
