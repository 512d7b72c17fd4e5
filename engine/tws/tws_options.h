// Options of the track-while-scan tracker (tws_tracker.h), with defaults and units.
//
//   field                      default    unit   meaning
//   dimensions                 2          -      2: track in x-y from (range, bearing);
//                                                3: x-y-z, every plot needs an elevation
//   noise.range_sigma_m        10         m      plot noise the conversion assumes
//   noise.bearing_sigma_rad    0.01       rad
//   noise.elevation_sigma_rad  0.01       rad    (dimensions 3)
//   conversion                 kUnbiased  -      polar_conversion.h
//   accel_noise_mps2           5          m/s^2  sigma_a of the constant-velocity model
//   filter                     kKalman    -      kSteadyState: freeze the gain once it
//                                                converges (updater.h)
//   steady_state_tolerance     1e-3       -      relative gain change that counts as converged
//   gate_probability           0.9995     -      P_G; the gate is g = chi^2_D quantile
//   confirm_hits, confirm_window 3, 5     scans  M of N: tentative -> confirmed
//   max_coast_scans            5          scans  a confirmed track is deleted after this
//                                                many misses in a row (P_D 0.9: a real
//                                                target misses 5 in a row once in 1e5 scans)
//   max_position_sigma_m       2000       m      any track is deleted when a position
//                                                variance exceeds this squared
//   initiation                 kOnePoint  -      kTwoPoint: pair plots of consecutive scans
//   initial_speed_sigma_mps    150        m/s    one-point: velocity prior std per axis
//   max_speed_mps              400        m/s    two-point: fastest target to pair plots for
//   max_initiations_per_scan   10000      -      tracks one scan may start (in plot order)
//   resume_misses              0          scans  a track that missed this many scans in a row
//                                                takes only plots that may resume a track
//                                                (CartesianPlot::may_resume_track); 0: any
//   coast_velocity_decay_s     0          s      a track that misses a scan has its velocity
//                                                scaled by exp(-dt / this) (and its velocity
//                                                covariance to match), so a coasting track
//                                                comes to rest within about velocity x this;
//                                                0: off (constant velocity while coasting,
//                                                the radar case). For targets that stop when
//                                                they fall silent (talkers), whose velocity
//                                                estimate is mostly the plots' scatter
//   max_tracks                 10000      -      a scan that would exceed it initiates fewer
//                                                (a TrackList of 10^4 tracks is ~3.6 MB)
// Bounds on one scan's work, so that no scan (adversarial or cluttered) costs more than
// O(plots + tracks x budget) time and memory (associator.h):
//   max_plots_per_scan         65536      -      a larger scan is refused (INVALID_ARGUMENT)
//   gate_search_budget         64         -      grid rows + plots one track's gate search
//                                                (and one two-point pairing) looks at; a gate
//                                                holding more is cluttered beyond what GNN
//                                                resolves, and keeps what it found
//   max_assignment_cells       65536      -      a gate cluster of tracks x plots above this
//                                                is matched greedily (by d^2), not optimally
//                                                (the optimal solver is cubic: 256^3 ~ 2e7)
#pragma once

#include <cstdint>

#include "engine/core/status.h"
#include "engine/tws/associator.h"
#include "engine/tws/deleter.h"
#include "engine/tws/initiator.h"
#include "engine/tws/polar_conversion.h"
#include "engine/tws/updater.h"

namespace localizer::engine::tws {

struct TwsOptions {
  int dimensions = 2;
  PolarNoise noise;
  Conversion conversion = Conversion::kUnbiased;
  double accel_noise_mps2 = 5.0;
  FilterForm filter = FilterForm::kKalman;
  double steady_state_tolerance = 1e-3;
  double gate_probability = 0.9995;
  int confirm_hits = 3;
  int confirm_window = 5;
  int max_coast_scans = 5;
  double max_position_sigma_m = 2000.0;
  Initiation initiation = Initiation::kOnePoint;
  double initial_speed_sigma_mps = 150.0;
  double max_speed_mps = 400.0;
  int max_tracks = 10000;
  int max_initiations_per_scan = 10000;
  int resume_misses = 0;
  double coast_velocity_decay_s = 0.0;
  int max_plots_per_scan = 65536;
  int64_t gate_search_budget = 64;
  int64_t max_assignment_cells = 65536;

  // INVALID_ARGUMENT naming the field and its value.
  Status Validate() const;

  // The options of each role the tracker composes (updater.h, initiator.h, deleter.h).
  UpdaterOptions updater() const { return {accel_noise_mps2, filter, steady_state_tolerance}; }
  InitiatorOptions initiator() const {
    return {initiation, initial_speed_sigma_mps, max_speed_mps, confirm_hits, confirm_window, gate_search_budget};
  }
  AssociatorLimits associator() const { return {gate_search_budget, max_assignment_cells}; }
  DeleterOptions deleter() const { return {confirm_hits, confirm_window, max_coast_scans, max_position_sigma_m}; }
};

}  // namespace localizer::engine::tws
