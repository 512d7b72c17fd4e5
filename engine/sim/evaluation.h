// Scores a session's estimates against the simulator's truth, in absolute terms and as a
// ratio to the per-frame Cramer–Rao bound.
//
// For each estimate the true TDOA of pair k is h_k at the truth for reception time
// t_s - d_k / 2 (the instant the pair describes). The measured TDOA spread of pair k,
// sigma_k, is the RMS of (measured - true) over the scored frames. The per-frame
// position CRLB at a frame is sqrt(trace((H^T R^-1 H)^-1)) with R = diag(sigma_k^2) and H the
// TDOA Jacobian at the true position: the best any unbiased single-frame fix can do. The
// score reports the RMS of that bound over the scored frames and RMSE / bound.
#pragma once

#include <functional>
#include <vector>

#include "engine/core/estimate.h"
#include "engine/sim/simulator.h"

namespace localizer::engine {

struct TrackScore {
  int scored = 0;             // initialised estimates at or after skip_s, inside the truth
  int reinitialisations = 0;  // estimates flagged reinitialised (whole run)
  double rmse_m = 0.0;
  double median_m = 0.0;
  double p95_m = 0.0;  // nearest-rank 95th percentile of the 3-D error
  double max_m = 0.0;
  double crlb_m = 0.0;  // RMS over scored frames of the per-frame position CRLB
  double rmse_over_crlb = 0.0;
  std::vector<double> tdoa_sigma_s;  // measured TDOA spread per pair
};

// Estimates before skip_s (convergence) are not scored.
TrackScore ScoreTrack(const ArrayGeometry& array, const SimResult& truth, const std::vector<Estimate>& estimates,
                      double skip_s);
// The same for an array that moves: array_at(t_s) is where it was at reception time t_s
// (a moving array's true pose: ArrayGeometry::Moved by the platform's attitude).
TrackScore ScoreTrack(const std::function<ArrayGeometry(double)>& array_at, const SimResult& truth,
                      const std::vector<Estimate>& estimates, double skip_s);

}  // namespace localizer::engine
