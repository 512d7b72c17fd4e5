// Kalman filters of the 2-D experiment, assembled from a predictor and an updater (Stone
// Soup's roles): {EKF, UKF} x {Gaussian, Huber, Student-t}.
//
// Predictors (process model: planar_filter.h; M = diag(speed_sigma^2, steering_sigma^2)):
//   EKF: x' = f(x, u),  P' = F P F^T + G M G^T  (F, G: bicycle_model.h).
//   UKF: the state augmented with the control errors, (x, y, theta, w_v, w_d) ~
//        N((x, 0, 0), blockdiag(P, M)); 2n + 1 = 11 sigma points of Wan & van der Merwe's
//        scaled set with alpha 1, beta 2, kappa 0 (lambda = 0: points at +-sqrt(5) columns of
//        the Cholesky root, mean weights 0 and 1/10, covariance weights 2 and 1/10, none
//        negative), each through f(x, u_cmd + w); mean and covariance from the weights.
// Measurement: z = H x + n, H = [I2 0], n assumed N(0, R), R = sigma_R^2 I2 (sigma_R: the
// sensor's nominal noise; the true noise is the mixture in mixture_noise.h).
// Updaters (prior x-, P-; residuals r = (z - H x) / sigma_R at the current estimate x):
//   Gaussian: K = P- H^T (H P- H^T + R)^-1, x = x- + K (z - H x-), Joseph-form P.
//   Huber / Student-t: iteratively reweighted least squares on the measurement rows only
//   (the prior is trusted): per axis weight w_i(r_i), R_w = R diag(1 / w_i), then the
//   Gaussian update with R_w, repeated from x- until the estimate moves < 1e-9 m (at most
//   10 times); P from the last R_w (Joseph form). This is the M-estimation view of the
//   Kalman update (Karlgaard & Schaub's Huber filter, reweighting the measurement only):
//     Huber:     w(r) = min(1, c / |r|),                   c = 1.345 (95 % Gaussian efficiency)
//     Student-t: w(r) = (nu + 1) / (nu + r^2),             nu = 3
//   (the t-weights are the EM weights of a Student-t likelihood with nu degrees of freedom
//   and scale sigma_R; they redescend, so a far outlier is nearly ignored).
// Heading is never wrapped (no heading is measured). Cost per predict + update, measured
// by the experiment: 0.2 us (EKF), 0.6 us (UKF), +0.25 us for the reweighting. Not
// thread-safe; one filter per run.
#pragma once

#include <memory>
#include <string>

#include "engine/experiments/planar_filter.h"

namespace localizer::engine::experiments {

enum class PlanarPredictor { kExtended, kUnscented };
enum class PlanarUpdater { kGaussian, kHuber, kStudentT };

struct PlanarKalmanOptions {
  PlanarPredictor predictor = PlanarPredictor::kExtended;
  PlanarUpdater updater = PlanarUpdater::kGaussian;
  double measurement_sigma_m = 1.0;  // sigma_R > 0
  double huber_threshold = 1.345;    // c > 0, in units of sigma_R
  double student_dof = 3.0;          // nu > 0

  Status Validate() const;  // INVALID_ARGUMENT naming the field
};

class PlanarKalmanFilter final : public PlanarFilter {
 public:
  static StatusOr<std::unique_ptr<PlanarKalmanFilter>> Create(const BicycleModel& model,
                                                              const ControlNoise& control_noise,
                                                              const PlanarKalmanOptions& options);
  PlanarKalmanFilter(const PlanarKalmanFilter&) = delete;
  PlanarKalmanFilter& operator=(const PlanarKalmanFilter&) = delete;

  void Initialise(const PlanarBelief& belief) override;
  void Predict(const BicycleControl& command, double dt_s) override;
  void Update(const Eigen::Vector2d& z_m) override;
  PlanarState Estimate() const override { return belief_.mean; }
  const PlanarBelief& belief() const { return belief_; }

 private:
  PlanarKalmanFilter(const BicycleModel& model, const ControlNoise& control_noise, const PlanarKalmanOptions& options)
      : model_(model), control_noise_(control_noise), options_(options) {}
  double Weight(double residual) const;  // the updater's w(r)

  BicycleModel model_;
  ControlNoise control_noise_;
  PlanarKalmanOptions options_;
  PlanarBelief belief_;
};

}  // namespace localizer::engine::experiments
