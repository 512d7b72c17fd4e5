// Several acoustic sources followed by direction, with identities: each frame's SRP-PHAT
// peaks (srp_phat.h) become plots for the track-while-scan roles (engine/tws: a
// constant-velocity Kalman filter per track, chi-square gate, global nearest neighbour,
// M-of-N confirmation, deletion after misses).
//
// A direction is tracked as a point on the unit circle or sphere (the Cartesian plot
// interface, TwsTracker::ProcessCartesian):
//   volumetric, planar  3-D: the peak's direction u, covariance sigma^2 (I - u u^T) +
//                       (sigma / 10)^2 u u^T (tangential noise; the radius is nearly known);
//   linear              2-D: (cos theta, sin theta) of the cone angle theta, the same way.
// So "metres" in the tracker are radians on the sphere: velocity is an angular rate
// (rad/s), accel_noise an angular acceleration (rad/s^2). A track's reported direction is
// its position normalised. Planar arrays without a stated side: the direction on the
// normal's side (the mirror is the same source).
//
// Defaults suit talkers around a board: sigma 0.05 rad (3 degrees, about a small board's
// frame-by-frame spread in a reverberant room), angular acceleration 2 rad/s^2, 3 of 5
// frames to confirm, deletion after max_coast_s of silence (1 s: pauses in speech keep their
// identity), and after the direction's variance exceeds (0.5 rad)^2.
// Not thread-safe; one per session. Deterministic.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "engine/core/status.h"
#include "engine/core/types.h"
#include "engine/doa/array_shape.h"
#include "engine/doa/srp_phat.h"
#include "engine/tws/track_report.h"
#include "engine/tws/tws_tracker.h"

namespace localizer::engine {

struct DirectionTrackerOptions {
  double peak_sigma_rad = 0.05;
  double angular_accel_noise_radps2 = 2.0;
  int confirm_hits = 3;
  int confirm_window = 5;
  double max_coast_s = 1.0;
  double frame_period_s = 0.016;  // hop / sample rate: turns max_coast_s into frames
  double initial_rate_sigma_radps = 1.0;

  Status Validate() const;
};

struct SourceTrack {
  static constexpr double kNan = DirectionPeak::kNan;
  uint64_t id = 0;  // 1, 2, 3, ... never reused
  tws::TrackStatus status = tws::TrackStatus::kTentative;
  Vec3 direction = Vec3::Constant(kNan);  // unit; NaN for linear arrays
  double azimuth_rad = kNan;
  double elevation_rad = kNan;
  double cone_angle_rad = kNan;  // linear arrays
  double sigma_rad = kNan;       // RMS angular standard deviation of the estimate
};

class DirectionTracker {
 public:
  // INVALID_ARGUMENT naming the option.
  static StatusOr<DirectionTracker> Create(ArrayShape shape, const DirectionTrackerOptions& options);

  // One frame's peaks at time t_s (after the previous frame's). Fills `out` with the
  // confirmed and coasting tracks (tentative ones too when asked), in order of id.
  Status Update(double t_s, const std::vector<DirectionPeak>& peaks, std::vector<SourceTrack>* out,
                bool include_tentative = false);

 private:
  DirectionTracker(ArrayShape shape, const DirectionTrackerOptions& options, std::unique_ptr<tws::TwsTracker> tracker)
      : shape_(shape), options_(options), tracker_(std::move(tracker)) {}
  ArrayShape shape_;
  DirectionTrackerOptions options_;
  std::unique_ptr<tws::TwsTracker> tracker_;
  std::vector<tws::CartesianPlot> plots_;
  std::vector<tws::TrackReport> reports_;
};

}  // namespace localizer::engine
