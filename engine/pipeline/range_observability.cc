#include "engine/pipeline/range_observability.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "engine/array/multilateration.h"

namespace localizer::engine {

double RangeSd(const ArrayGeometry& array, const Vec3& at_m, const Mat3& covariance_m2) {
  const Vec3 line_m = at_m - array.centroid_m();
  const double range_m = line_m.norm();
  if (!(range_m > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  const Vec3 u = line_m / range_m;
  return std::sqrt(std::max(0.0, u.dot(covariance_m2 * u)));
}

RangeObservability JudgeRange(const ArrayGeometry& array, const Vec3& position_m, const Eigen::VectorXd& pair_sigma_s) {
  RangeObservability out;
  out.range_m = (position_m - array.centroid_m()).norm();
  const auto pairs = static_cast<Eigen::Index>(array.pair_count());
  if (!(out.range_m > 0.0) || pair_sigma_s.size() != pairs) return out;
  // A pair left out weighs nothing: a sigma of a second is 10^3 x any array's reach.
  constexpr double kLeftOut_s = 1.0;
  Eigen::VectorXd sigma_s(pairs);
  int usable = 0;
  for (Eigen::Index p = 0; p < pairs; ++p) {
    const bool usable_pair = pair_sigma_s(p) > 0.0 && std::isfinite(pair_sigma_s(p));
    sigma_s(p) = usable_pair ? pair_sigma_s(p) : kLeftOut_s;
    usable += usable_pair;
  }
  if (usable < 3) return out;  // fewer than 3 pairs cannot bound a 3-D position at all
  const double sd_m = RangeSd(array, position_m, TdoaPositionCrlb(array, position_m, sigma_s));
  if (!std::isfinite(sd_m)) return out;
  out.range_sd_m = sd_m;
  out.far_field = out.range_sd_m > kFarFieldRangeShare * out.range_m;
  return out;
}

void PairSigmaHistory::Add(const Measurement& measurement, double fallback_sigma_s) {
  const auto pairs = static_cast<Eigen::Index>(measurement.pairs.size());
  if (!frames_.empty() && frames_.front().size() != pairs) Reset();
  // The slot this frame takes: a new one until the ring is full, then the oldest (next_).
  size_t slot = next_;
  if (frames_.size() < static_cast<size_t>(kFrames)) {
    frames_.emplace_back(pairs);
    slot = frames_.size() - 1;
  } else {
    next_ = (next_ + 1) % frames_.size();
  }
  Eigen::VectorXd& sigma_s = frames_[slot];
  for (Eigen::Index p = 0; p < pairs; ++p) {
    const PairMeasurement& pair = measurement.pairs[static_cast<size_t>(p)];
    const double own = pair.delay_sigma_s > 0.0 ? pair.delay_sigma_s : fallback_sigma_s;
    sigma_s(p) = pair.peak_value > 0.0 ? own : 0.0;
  }
}

Eigen::VectorXd PairSigmaHistory::Median() const {
  if (frames_.empty()) return {};
  const Eigen::Index pairs = frames_.front().size();
  Eigen::VectorXd out = Eigen::VectorXd::Zero(pairs);
  std::vector<double> values;
  for (Eigen::Index p = 0; p < pairs; ++p) {
    values.clear();
    for (const Eigen::VectorXd& frame : frames_) {
      if (frame(p) > 0.0 && std::isfinite(frame(p))) values.push_back(frame(p));
    }
    if (values.empty()) continue;
    const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
    std::nth_element(values.begin(), middle, values.end());
    out(p) = *middle;
  }
  return out;
}

}  // namespace localizer::engine
