#include "engine/pipeline/platform_pose.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace localizer::engine {
namespace {

// (roll, pitch, yaw) of R = Rz(yaw) Ry(pitch) Rx(roll).
Vec3 EulerZyx(const Eigen::Quaterniond& q) {
  const Mat3 r = q.toRotationMatrix();
  return Vec3(std::atan2(r(2, 1), r(2, 2)), std::asin(std::clamp(-r(2, 0), -1.0, 1.0)), std::atan2(r(1, 0), r(0, 0)));
}

}  // namespace

PlatformPose::PlatformPose(std::unique_ptr<AttitudeFilter> filter, const Vec3& origin_m)
    : filter_(std::move(filter)), origin_m_(origin_m), last_t_s_(-std::numeric_limits<double>::infinity()) {}

StatusOr<std::unique_ptr<PlatformPose>> PlatformPose::Create(const AttitudeFilterOptions& options,
                                                             const Vec3& origin_m) {
  if (!origin_m.allFinite()) return InvalidArgument("platform origin_m must be finite");
  auto filter = CreateAttitudeFilter(options);
  if (!filter.ok()) return filter.status();
  return std::unique_ptr<PlatformPose>(new PlatformPose(std::move(filter).value(), origin_m));
}

Status PlatformPose::Add(const std::vector<ImuSample>& samples) {
  double previous = last_t_s_;
  for (size_t i = 0; i < samples.size(); ++i) {
    const Status status = ValidateImuSample(samples[i], previous);
    if (!status.ok()) return InvalidArgument("imu sample " + std::to_string(i) + ": " + status.message());
    previous = samples[i].t_s;
  }
  for (const ImuSample& sample : samples) {
    LOCALIZER_RETURN_IF_ERROR(filter_->Update(sample));  // validated: cannot fail
    const AttitudeEstimate e = filter_->estimate();
    history_.push_back({sample.t_s, e.body_to_world, e.sd_rad});
    last_t_s_ = sample.t_s;
  }
  while (history_.size() > 2 && history_.back().t_s - history_[1].t_s > kHistory_s) history_.pop_front();
  while (history_.size() > kMaxHistorySamples) history_.pop_front();
  return Status::Ok();
}

Status PlatformPose::SetOrigin(const Vec3& origin_m) {
  if (!origin_m.allFinite()) return InvalidArgument("platform origin_m must be finite");
  origin_m_ = origin_m;
  return Status::Ok();
}

std::optional<PlatformAttitude> PlatformPose::At(double t_s) const {
  if (history_.empty()) return std::nullopt;
  PlatformAttitude state;
  state.origin_m = origin_m_;
  const Stamped* chosen = &history_.back();
  if (t_s <= history_.front().t_s) {
    chosen = &history_.front();
  } else if (t_s < history_.back().t_s) {
    // The first sample after t (history is short: a linear scan from the back is cheap for
    // frames near the newest samples, where they almost always are).
    size_t after = history_.size() - 1;
    while (after > 0 && history_[after - 1].t_s >= t_s) --after;
    const Stamped& a = history_[after - 1];
    const Stamped& b = history_[after];
    const double u = (t_s - a.t_s) / (b.t_s - a.t_s);
    state.body_to_world = a.q.slerp(u, b.q).normalized();
    state.euler_rad = EulerZyx(state.body_to_world);
    state.euler_sd_rad = (1.0 - u) * a.sd_rad + u * b.sd_rad;
    return state;
  }
  state.body_to_world = chosen->q;
  state.euler_rad = EulerZyx(chosen->q);
  state.euler_sd_rad = chosen->sd_rad;
  return state;
}

}  // namespace localizer::engine
