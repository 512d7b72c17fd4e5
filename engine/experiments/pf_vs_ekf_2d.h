// The seed's 2-D experiment: a particle filter against Kalman filters when position fixes
// carry impulsive, skewed (alpha-stable / Gaussian mixture) noise.
//
// One Monte-Carlo run r (all draws keyed by (seed, stream, r): experiment_random.h):
//   truth    s_0 = (0, 0, 0); s_k+1 = f(s_k, u_k + w_k), u_k the closed course's commands
//            (closed_course.h), w_k the control errors (planar_filter.h), k = 0 .. K-1;
//   fixes    z_k+1 = (x, y)(s_k+1) + n_k+1, n from the mixture (mixture_noise.h);
//   filters  each starts from N(s_0, diag(sp^2, sp^2, sh^2)) (the start is known, the
//            prior is not over-confident), then Predict(u_k), Update(z_k+1) per step;
//   error    e_k+1 = |(x, y)(estimate after the update) - (x, y)(s_k+1)|, metres.
// Per filter, over all runs:
//   mean_error_m            mean of e over every step of every run (the seed's figure);
//   step_std_m              std of those per-step errors, pooled over steps and runs
//                           (the seed's "sd": its PF sd/mean = 0.65 is that of per-step
//                           errors; per-run means would scatter far less);
//   run_std_m               std over runs of each run's mean error;
//   median_error_m          median of the pooled per-step errors;
//   divergences             runs whose mean error over the final lap exceeds
//                           divergence_error_m (5 m, 5 sigma of the good sensor: a filter
//                           that has lost the vehicle rather than one that is noisy);
//   us_per_step             wall time of Predict + Update, averaged (not reproducible; the
//                           errors are, bit for bit, for a seed and build).
// Filters (names are the table's first column):
//   PF         bootstrap PF, N particles, true mixture likelihood (planar_particle.h)
//   PF-Gauss   the same PF with the Kalman filters' Gaussian likelihood (ablation)
//   EKF, UKF   Gaussian update with R = sigma_R^2 I2 (planar_kalman.h)
//   EKF-Huber, UKF-Huber, EKF-t   robust updates (Huber c, Student-t nu)
// sigma_R, the Kalman filters' nominal sensor noise, defaults to the Gaussian component's
// sigma: the noise a designer who calibrated the sensor on its good days would assume.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "engine/core/status.h"
#include "engine/experiments/bicycle_model.h"
#include "engine/experiments/closed_course.h"
#include "engine/experiments/mixture_noise.h"
#include "engine/experiments/planar_filter.h"

namespace localizer::engine::experiments {

struct PfVsEkf2dOptions {
  int runs = 100;  // Monte-Carlo runs, 1..10^6
  uint64_t seed = 1;
  BicycleModel model;                       // wheelbase 2.5 m
  CourseOptions course;                     // 3.5 m/s, 0.1 s, 2 laps of a rounded square
  ControlNoise control_noise;               // 0.1 m/s, 0.02 rad: truth and filters
  MixtureNoise measurement_noise;           // e 0.5, sigma 1 m, S1(1.7, 1, 10 m, -3 m)
  int particles = 100;                      // seed: 100
  double resample_ess_fraction = 0.5;       // PFs resample below ESS = 0.5 N
  double kalman_sigma_m = 0.0;              // sigma_R; 0: measurement_noise.gaussian_sigma_m
  double huber_threshold = 1.345;           // c, units of sigma_R
  double student_dof = 3.0;                 // nu
  double initial_position_sigma_m = 0.5;    // sp: filters' prior std of x and y at the start
  double initial_heading_sigma_rad = 0.05;  // sh
  double divergence_error_m = 5.0;          // final-lap mean error that counts as diverged
  std::vector<std::string> filters;         // names to run, in this order; empty: all

  // INVALID_ARGUMENT naming the field (runs, particles, kalman_sigma_m, ..., filters with
  // the unknown name) or the nested options' errors.
  Status Validate() const;
  double KalmanSigma() const { return kalman_sigma_m > 0.0 ? kalman_sigma_m : measurement_noise.gaussian_sigma_m; }
};

// Every filter the experiment knows, in table order.
std::vector<std::string> PfVsEkf2dFilterNames();

// One run's truth, commands and fixes (index k: after step k; truth[0] is the start).
struct PlanarRun {
  std::vector<BicycleControl> commands;  // K
  std::vector<PlanarState> truth;        // K + 1
  std::vector<Eigen::Vector2d> fixes_m;  // K (fix k is of truth[k + 1])
};
StatusOr<PlanarRun> SimulatePlanarRun(const PfVsEkf2dOptions& options, int64_t run);

// The named filter for run `run` (its random engine keyed by seed and run). `mixture` is
// needed (non-null) by "PF" only. INVALID_ARGUMENT for an unknown name.
StatusOr<std::unique_ptr<PlanarFilter>> MakePlanarFilter(const std::string& name, const PfVsEkf2dOptions& options,
                                                         std::shared_ptr<const MixtureDensity> mixture, int64_t run);

// Initialises `filter` at the options' prior and runs it over `run`: the K position errors.
std::vector<double> TrackPlanarRun(PlanarFilter& filter, const PfVsEkf2dOptions& options, const PlanarRun& run);

struct FilterSummary {
  std::string name;
  double mean_error_m = 0.0;
  double step_std_m = 0.0;
  double run_std_m = 0.0;
  double median_error_m = 0.0;
  double final_lap_error_m = 0.0;  // mean over runs of the final lap's mean error
  int divergences = 0;
  double us_per_step = 0.0;
};

struct PfVsEkf2dResult {
  std::vector<FilterSummary> filters;
  int runs = 0;
  int steps_per_run = 0;
  int steps_per_lap = 0;
};

// Runs the experiment; `progress(runs_done)` after each run when set. Single-threaded.
StatusOr<PfVsEkf2dResult> RunPfVsEkf2d(const PfVsEkf2dOptions& options, const std::function<void(int)>& progress = {});

}  // namespace localizer::engine::experiments
