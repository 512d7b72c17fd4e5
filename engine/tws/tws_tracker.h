// Track-while-scan: multi-target tracking of radar/sonar plots with one constant-velocity
// Kalman filter per track. The tracker only composes the roles (Stone Soup's
// tracker/simple.py shape); each lives in its own header, with its contract:
//   measurement model   polar / spherical -> Cartesian, unbiased   polar_conversion.h
//   updater             predict, update, coast; steady-state form  updater.h (cv_kalman.h)
//   associator          chi^2 gate, clusters, global nearest nbr   associator.h (chi_square.h,
//                                                                  point_grid.h, clustering.h,
//                                                                  assignment.h)
//   initiator           one-point or two-point; M-of-N confirm     initiator.h (track_history.h)
//   deleter             M-of-N, misses in a row, covariance bound  deleter.h
// The roles know nothing of radars: they trade Gaussians (gaussian.h), a mean and its
// covariance, whether a converted plot or a track's expected measurement.
//
// One scan at time t (Process):
//  1. every track predicts to t (dt = t - previous scan's time);
//  2. plots are converted to world-frame positions with covariance R_j;
//  3. confirmed and coasting tracks are gated against all plots (those that missed
//     resume_misses scans in a row, when > 0, after the others and only against plots that
//     may resume a track): d^2 = nu^T (A + R_j)^-1 nu
//     <= g, g = chi^2_D quantile of gate_probability; the gate graph's connected components
//     are solved alone by SolveGnn with cost d^2 and miss cost g (a plot inside the gate is
//     always preferred to a miss, and the total of d^2 over the scan is minimal);
//  4. tentative tracks do the same with the plots left over (a clutter-born tentative track
//     never takes a confirmed track's plot);
//  5. tracks with a plot update; the others coast (with coast_velocity_decay_s > 0 their
//     velocity, and its covariance, decays by exp(-dt / coast_velocity_decay_s) per miss);
//  6. status: tentative -> confirmed with M hits of the last N scans; a tentative track
//     that can no longer reach M is deleted; a confirmed track is deleted after
//     max_coast_scans misses in a row; any track whose position variance exceeds
//     max_position_sigma_m^2 is deleted;
//  7. plots still left (and allowed to: CartesianPlot::may_start_track), at most
//     max_initiations_per_scan of them in plot order, initiate tentative tracks: one-point (x = (z, 0), P = diag(R,
//     sigma_v^2 I)) or two-point (paired with a leftover plot of the previous scan within
//     max_speed dt: v = (z2 - z1)/dt, P from both R); unpaired two-point plots wait one scan.
// Clutter and P_D < 1 are handled by the gate (clutter rarely falls in it), by coasting
// and by M-of-N (clutter rarely repeats near a prediction).
//
// Cost per scan: O(T + M) for prediction, conversion and the grid, plus the gate tests of
// the plots inside each track's box, plus the assignment of each multi-track cluster
// (cubic in its size, clusters are small unless targets crowd). Work arrays persist
// between scans: a steady scene allocates nothing per scan but the output.
// Not thread-safe; one tracker per session. Deterministic: no random draws.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <vector>

#include "engine/core/detection.h"
#include "engine/core/status.h"
#include "engine/tws/track_report.h"
#include "engine/tws/tws_options.h"

namespace localizer::engine::tws {

// A plot already in the world frame (Cartesian measurement model): position and its
// covariance. A 2-D tracker reads the x-y part. may_start_track false: the plot may update
// a track but starts none when no track takes it (a caller that knows a plot is unlikely to
// be a new target, e.g. a reflection, says so).
struct CartesianPlot {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Matrix3d covariance_m2 = Eigen::Matrix3d::Identity();
  bool may_start_track = true;
  // false: the plot may not update a track that has missed TwsOptions::resume_misses (> 0)
  // scans in a row (a caller that knows a plot is not a silent target resuming, e.g. a
  // steady reflection of another, says so).
  bool may_resume_track = true;
};

class TwsTracker {
 public:
  // INVALID_ARGUMENT when the options do not validate.
  static StatusOr<std::unique_ptr<TwsTracker>> Create(const TwsOptions& options);
  virtual ~TwsTracker() = default;
  TwsTracker(const TwsTracker&) = delete;
  TwsTracker& operator=(const TwsTracker&) = delete;

  // One scan of polar plots. INVALID_ARGUMENT (the tracker unchanged) when scan.time_s is
  // not finite or not after the previous scan's, a range is not finite and > 0, an angle is
  // not finite, or a 3-D tracker gets a plot without elevation (a 2-D tracker ignores
  // elevations and uses ground range r cos(elevation)).
  virtual Status Process(const Scan& scan, ScanSummary* summary = nullptr) = 0;
  // One scan of Cartesian plots (covariances symmetric positive definite; not checked
  // beyond finiteness).
  virtual Status ProcessCartesian(double time_s, const std::vector<CartesianPlot>& plots,
                                  ScanSummary* summary = nullptr) = 0;

  // The tracks after the latest scan, in order of id; tentative ones only when asked.
  // Fills `out` (cleared first; its capacity is reused).
  virtual void Tracks(std::vector<TrackReport>* out, bool include_tentative = true) const = 0;
  std::vector<TrackReport> Tracks(bool include_tentative = true) const {
    std::vector<TrackReport> out;
    Tracks(&out, include_tentative);
    return out;
  }

  virtual const TwsOptions& options() const = 0;
  virtual int track_count() const = 0;
  virtual int64_t total_track_updates() const = 0;

 protected:
  TwsTracker() = default;
};

}  // namespace localizer::engine::tws
