// Whether a frame's TDOAs can tell how far the source is (Estimate::far_field, range_sd_m).
//
// A TDOA array measures the wavefront's curvature, which falls as 1/range: beyond a few
// apertures the data fix the direction and 1/range (nearly Gaussian), not the range. The
// test is the Cramer-Rao bound of one frame's TDOAs at the estimate, projected on the line
// of sight from the array's centroid: when it exceeds kFarFieldRangeShare of the range,
// 1/range is within three of its sigmas of zero, so nothing in a frame bounds the range from
// above. Each pair's sigma is the median of its last frames' own delay sigmas
// (PairSigmaHistory): one frame's sigma swings several-fold at low SNR, and the flag would
// flicker with it.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "engine/array/array_geometry.h"
#include "engine/core/far_field.h"
#include "engine/core/measurement.h"
#include "engine/core/types.h"

namespace localizer::engine {

struct RangeObservability {
  double range_m = 0.0;     // position - centroid
  double range_sd_m = 0.0;  // the frame's bound on it; 0 when it cannot be computed
  bool far_field = false;   // range_sd_m > kFarFieldRangeShare * range_m
};

// The standard deviation along the line of sight from the array's centroid to `at_m` of a
// position covariance (m^2); NaN at the centroid.
double RangeSd(const ArrayGeometry& array, const Vec3& at_m, const Mat3& covariance_m2);

// The bound with one delay sigma per pair (seconds; 0 or non-finite: the pair is left out).
// Fewer than 3 pairs, or a position on the centroid: range_sd_m 0 and not far field.
RangeObservability JudgeRange(const ArrayGeometry& array, const Vec3& position_m, const Eigen::VectorXd& pair_sigma_s);

// Each pair's delay sigma over the last kFrames measured frames: the median of those in
// which the pair had a peak (PairMeasurement::peak_value > 0), its own delay_sigma_s or,
// without one, the fallback (the sigma the tracker assumed). Bounded: kFrames per pair.
class PairSigmaHistory {
 public:
  static constexpr int kFrames = 8;
  void Add(const Measurement& measurement, double fallback_sigma_s);
  // One per pair of the last Add (0: no peak in the window).
  Eigen::VectorXd Median() const;
  void Reset() {
    frames_.clear();
    next_ = 0;
  }

 private:
  std::vector<Eigen::VectorXd> frames_;  // up to kFrames, written in place
  size_t next_ = 0;                      // the oldest once the ring is full
};

}  // namespace localizer::engine
