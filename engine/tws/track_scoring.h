// Identity bookkeeping of a tracker against truth, scan by scan: identity switches and
// track purity.
//
// Each scan (Add), the CLEAR-MOT correspondence (Bernardin & Stiefelhagen 2008): a truth
// keeps the track it was last paired with while that track exists and is within
// max_distance_m; the truths and tracks left are paired by an optimal assignment of squared
// distance (assignment.h, GNN with miss cost max_distance_m^2), pairs farther apart than
// max_distance_m left unpaired. (Without the first step two targets crossing within the
// noise would swap their nearest tracks every scan and count switches the tracker never
// made.)
//   identity switch: a truth paired with a track id other than the one it was last paired
//     with (a truth's first pairing is not a switch; a gap without a pairing is not one
//     either if the same id returns);
//   purity of a track: the largest fraction of its paired scans spent on one truth;
//     Purity() = sum over tracks of that largest count / all paired scans (1 = every track
//     followed one target only).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <vector>

namespace localizer::engine::tws {

struct Labelled {
  uint64_t id = 0;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
};

class TrackScoring {
 public:
  explicit TrackScoring(double max_distance_m) : max_distance_m_(max_distance_m) {}

  void Add(const std::vector<Labelled>& truth, const std::vector<Labelled>& tracks);

  int identity_switches() const { return switches_; }
  double Purity() const;  // 1 when nothing was paired
  int64_t paired() const { return paired_; }

 private:
  double max_distance_m_;
  int switches_ = 0;
  int64_t paired_ = 0;
  std::map<uint64_t, uint64_t> last_track_of_truth_;
  std::map<uint64_t, std::map<uint64_t, int64_t>> counts_;  // track -> truth -> scans
};

}  // namespace localizer::engine::tws
