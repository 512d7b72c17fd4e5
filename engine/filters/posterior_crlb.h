// Posterior Cramér–Rao lower bound (PCRLB) of a tracker on the TDOA measurement model, by
// Tichavský, Muravchik & Nehorai's recursion (IEEE Trans. Signal Process. 46:1386, 1998),
// so tracking accuracy can be stated as a ratio to the best any estimator could do.
//
// For x' = f(x) + w, w ~ N(0, Q), and z = h(x) + e, e ~ N(0, R), the Fisher information
// J_k of the state at step k obeys
//     J_{k+1} = D22 - D21 (J_k + D11)^-1 D12,
//     D11 = F^T Q^-1 F,  D12 = D21^T = -F^T Q^-1,  D22 = Q^-1 + H^T R^-1 H,
// with F = df/dx and H = dh/dx at the true state. By the matrix inversion lemma this is
//     J_{k+1} = (Q + F J_k^-1 F^T)^-1 + H^T R^-1 H,
// the form used here because the motion models' Q are singular (white acceleration drives
// six states with three noises). The bound on the state's error covariance is J_k^-1.
//
// The expectations over true trajectories are replaced by the one true trajectory the
// caller gives (the simulator's, deterministic), with the motion model and process noise
// the filter assumes: the bound for that model along that path. The measurement at step k
// is the TDOA of every pair with noise sigma_s(p), Jacobian (engine/filters/kalman_filter.h)
//     H_p = [grad T_p(p)^T, -(d_p / 2) grad T_p(p)^T, 0 ...],  d_p = T_p(p) the true delay,
// the velocity term being the instant-of-the-pair correction the filters also model.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "engine/array/array_geometry.h"
#include "engine/core/status.h"
#include "engine/models/motion_model.h"

namespace localizer::engine {

// One step of the true trajectory: its time and the full state in the motion model's
// layout (position, velocity, then the model's extra entries, e.g. acceleration or turn rate).
struct TrueState {
  double t_s = 0.0;
  Eigen::VectorXd state;
};

// The bound at each step of `truth`: state error covariance J_k^-1 (state_dim square).
// initial_information is J_0 at truth[0] (the prior, e.g. the first fix's information and
// the initial velocity spread), already including truth[0]'s measurement if the filter
// uses it. INVALID_ARGUMENT when truth is empty, times decrease, a state has the wrong size,
// sigma_s has a size other than the array's pair count or a non-positive entry, or
// initial_information is not square of state_dim; FAILED_PRECONDITION when an information
// matrix stops being invertible (no measurement information and no prior in some direction).
StatusOr<std::vector<Eigen::MatrixXd>> PosteriorCrlb(const ArrayGeometry& array, const MotionModel& model,
                                                     const std::vector<TrueState>& truth,
                                                     const Eigen::VectorXd& sigma_s,
                                                     const Eigen::MatrixXd& initial_information);

// The TDOA measurement's information H^T R^-1 H at a true state (state_dim square).
Eigen::MatrixXd TdoaInformation(const ArrayGeometry& array, const Eigen::VectorXd& state,
                                const Eigen::VectorXd& sigma_s);

}  // namespace localizer::engine
