// Where a moving array is at a frame's instant: its platform's attitude from the IMU samples
// streamed beside the blocks, and its origin in the world when the client gives it.
//
// The array's sensor positions are configured in the platform's body frame (the IMU's axes,
// engine/core/imu.h); at time t the world positions are
//     m_world = R(t) m_body + origin_m,   R(t) = attitude body -> world at t.
// IMU samples go through an attitude filter (engine/attitude/attitude_filter.h) as they
// arrive; each filtered attitude is kept for a few seconds (kHistory_s, and at most
// kMaxHistorySamples of them: memory stays bounded however fast a client stamps its
// samples) so that a frame whose centre lies
// between two samples gets their interpolation (slerp), whichever arrived first. A frame
// after the newest sample holds the newest attitude (send each block's IMU samples before
// the block); a frame before any sample has no pose (Pose returns nothing).
// Times are seconds on the session clock (0 = the session's first sample).
// Not thread-safe: owned by one session.
#pragma once

#include <cstddef>
#include <deque>
#include <memory>
#include <optional>
#include <vector>

#include "engine/attitude/attitude_filter.h"
#include "engine/core/estimate.h"
#include "engine/core/imu.h"
#include "engine/core/status.h"
#include "engine/core/types.h"

namespace localizer::engine {

class PlatformPose {
 public:
  static StatusOr<std::unique_ptr<PlatformPose>> Create(const AttitudeFilterOptions& options, const Vec3& origin_m);

  // Validates every sample first (finite, times increasing from the previous call's last);
  // on INVALID_ARGUMENT (naming the sample and field) nothing is consumed.
  Status Add(const std::vector<ImuSample>& samples);
  // The body origin from now on (a GNSS fix of a drifting buoy, say); INVALID_ARGUMENT when
  // not finite.
  Status SetOrigin(const Vec3& origin_m);
  // The pose at t_s, or nothing before the first IMU sample.
  std::optional<PlatformAttitude> At(double t_s) const;
  // Attitudes kept for interpolation: the last kHistory_s, at most kMaxHistorySamples.
  size_t history_size() const { return history_.size(); }
  static constexpr size_t kMaxHistorySamples = size_t{1} << 16;  // 5 s at 13 kHz; 4 MiB

 private:
  PlatformPose(std::unique_ptr<AttitudeFilter> filter, const Vec3& origin_m);

  struct Stamped {
    double t_s;
    Eigen::Quaterniond q;
    Vec3 sd_rad;
  };
  static constexpr double kHistory_s = 5.0;

  std::unique_ptr<AttitudeFilter> filter_;
  std::deque<Stamped> history_;  // ascending t_s, the last kHistory_s seconds
  Vec3 origin_m_;
  double last_t_s_;
};

}  // namespace localizer::engine
