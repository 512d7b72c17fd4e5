// What the tracker reports per track, and per scan.
//
// Status: kTentative until M of the last N scans (since its first plot) brought it a plot;
// then kConfirmed; kCoasting when confirmed but missed on the latest scan (its estimate is
// a prediction). Identities are 1, 2, 3, ... in order of initiation, never reused by one
// tracker.
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "engine/core/track_status.h"

namespace localizer::engine::tws {

using engine::TrackStatus;  // engine/core/track_status.h: shared with direction sessions
using engine::TrackStatusName;

struct TrackReport {
  uint64_t id = 0;
  TrackStatus status = TrackStatus::kTentative;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();  // world frame; z = 0 in 2-D
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();
  // Of (x, y, z, vx, vy, vz); in 2-D the z and vz rows and columns are 0.
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
  int hits = 0;                // plots assigned over the track's life
  int consecutive_misses = 0;  // scans since its last plot
  double time_s = 0.0;         // the instant the estimate describes (the latest scan)
  bool steady_state = false;   // its gain is frozen (FilterForm::kSteadyState)
};

struct ScanSummary {
  int plots = 0;
  int assigned = 0;   // plots that updated a track
  int initiated = 0;  // new tentative tracks
  int deleted = 0;
  int confirmed = 0;  // confirmed + coasting tracks after the scan
  int tentative = 0;
  int clusters = 0;           // gate-graph components with >= 1 edge
  int largest_cluster = 0;    // tracks in the largest of them
  int truncated_gates = 0;    // tracks whose gate search ran out of its budget (clutter)
  int greedy_clusters = 0;    // components matched greedily, too large to solve optimally
  int64_t track_updates = 0;  // tracks that went through the scan's cycle (predict, gate,
                              // update or coast); the unit of "track updates per second"
};

}  // namespace localizer::engine::tws
