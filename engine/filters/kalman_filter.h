// Extended and unscented Kalman filters on the TDOA measurement model, over any motion
// model (engine/models/motion_model.h): Stone Soup's roles with one class per filter type
// (the predictor and updater of each variant live in kalman_filter.cc).
//
// Measurement: for each pair k whose peak_snr >= min_peak_snr (engine/filters/pair_noise.h),
// the TDOA at the instant the pair describes (d_k / 2 before the frame centre, as the
// particle filter), to first order:
//     h_k(x) = T_k(p) - (d_k / 2) grad T_k(p) . v,   T_k(p) = (|p - m_k| - |p - m_ref|) / c,
// with noise R = diag(sigma_k^2), sigma_k fixed or adapted online as the particle filter's.
//   EKF: H = [grad T_k, -(d_k / 2) grad T_k, 0] (the correction's own curvature neglected).
//   UKF: 2n + 1 sigma points (Wan & van der Merwe's scaled set, alpha 1, beta 2, kappa 0:
//        all weights non-negative, so P stays positive semi-definite), through both the
//        motion model and h.
// Update (both): innovation nu = z - h, S = H P H^T + R, gate: the update is skipped
// (UpdateReport.gated; nis and pair_count still reported, so a lost track that gates every
// frame trips the session's divergence test) when nu^T S^-1 nu exceeds the chi-square
// quantile gate_p with that many degrees of freedom; else K = P H^T S^-1 and, for the EKF, the Joseph form
//     P <- (I - K H) P (I - K H)^T + K R K^T,
// for the UKF P <- P - K S K^T; both then symmetrised, and an eigenvalue floor (1e-12 of the
// largest) repairs a covariance that rounding pushed indefinite. nis = nu^T S^-1 nu.
// Robust update (robust != kNone; an M-estimator by iterated reweighting): the measurement
// noise of pair k is inflated to R_k / w_k, with e_k = |z_k - h_k(x+)| / sigma_k the
// residual at the updated mean in noise stds and
//     kHuber:    w_k = min(1, c / e_k),                 c = huber_threshold (1.345: 95 %
//                                                        efficiency on Gaussian noise)
//     kStudentT: w_k = min(1, (nu + 1) / (nu + e_k^2)), nu = student_dof (4, the particle
//                                                        filter's peak likelihood)
// Starting from w = 1 (the plain update), x+ and w are recomputed until no weight moves by
// 1e-3 (at most 10 passes); then P is updated with the final R. A pair the others
// contradict thus loses its pull while consistent pairs keep w = 1: Huber bounds each
// pair's influence (its chi-square share grows as c e_k), Student-t redescends (a gross
// outlier's share tends to nu + 1). The gate then tests nu^T S_w^-1 nu with the reweighted
// S_w, so a frame with one bad pair is used rather than dropped (Huber: up to moderate
// outliers, ~10 sigma on 7 pairs; Student-t: any); report.nis stays the plain NIS.
// Log-likelihood of the frame (last_log_likelihood(), read by the IMM): the Gaussian
//     log N(nu; 0, S) = -(nu^T S^-1 nu + log det S + m log 2 pi) / 2,  m = pairs used,
// with the S the gain used (S_w when robust), computed whether or not the gate refuses.
// Cost per update: a few microseconds (n <= 9 states, <= 15 pairs; BENCHMARKS.md).
// Not thread-safe; one filter per session.
#pragma once

#include <memory>
#include <string>

#include "engine/array/array_geometry.h"
#include "engine/filters/pair_noise.h"
#include "engine/filters/tracker.h"
#include "engine/models/motion_model.h"

namespace localizer::engine {

// Names on the wire and in flags: ekf (kExtended), ukf (kUnscented).
enum class KalmanVariant { kExtended, kUnscented };
// INVALID_ARGUMENT "<field> 'x' is not one of: ekf, ukf".
StatusOr<KalmanVariant> ParseKalmanVariant(const std::string& name, const std::string& field);
const char* KalmanVariantName(KalmanVariant variant);

// Names on the wire and in flags: none, huber, student-t.
enum class RobustUpdate { kNone, kHuber, kStudentT };
// INVALID_ARGUMENT "<field> 'x' is not one of: none, huber, student-t".
StatusOr<RobustUpdate> ParseRobustUpdate(const std::string& name, const std::string& field);
const char* RobustUpdateName(RobustUpdate robust);

struct KalmanOptions {
  KalmanVariant variant = KalmanVariant::kExtended;
  MotionModelKind motion_model = MotionModelKind::kCv;
  MotionModelOptions motion;                  // its noise parameters
  double tdoa_sigma_s = 0.0;                  // TDOA noise std; 0: adaptive (pair_noise.h)
  double min_peak_snr = 5.0;                  // pairs below are left out
  double gate_probability = 0.9999;           // chi-square gate on the whole innovation, in (0, 1]; 1: no gate
  double extra_state_std = 1.0;               // initial std of the model's entries beyond (p, v):
                                              // m/s^2 for acceleration, rad/s for the turn rate
  RobustUpdate robust = RobustUpdate::kNone;  // reweighted pairs (above)
  double huber_threshold = 1.345;             // c, in noise stds, > 0 (robust kHuber only)
  double student_dof = 4.0;                   // nu, > 0 (robust kStudentT only)

  Status Validate() const;  // INVALID_ARGUMENT naming the field
};

class KalmanFilter final : public Tracker {
 public:
  static StatusOr<std::unique_ptr<KalmanFilter>> Create(const ArrayGeometry& array, const KalmanOptions& options);
  ~KalmanFilter() override;
  KalmanFilter(const KalmanFilter&) = delete;
  KalmanFilter& operator=(const KalmanFilter&) = delete;

  bool initialised() const override;
  Status Initialise(const TrackState& belief) override;
  Status SetArray(const ArrayGeometry& array) override;
  void Predict(double dt_s) override;
  StatusOr<UpdateReport> Update(const Measurement& measurement) override;
  TrackState State() const override;

  // The full state and covariance (state_dim() entries: (p, v) then the model's extras).
  const Eigen::VectorXd& mean() const;
  const Eigen::MatrixXd& covariance() const;
  int state_dim() const;
  const char* motion_model_name() const;  // "cv", "ca", "ct", "singer"
  // Replaces the full state (state_dim() entries) and covariance, and marks the filter
  // initialised (the IMM's mixing step). INVALID_ARGUMENT for a wrong size, a non-finite
  // entry or a covariance that is not positive semi-definite; the filter is then unchanged.
  Status SetState(const Eigen::VectorXd& mean, const Eigen::MatrixXd& covariance);
  // log N(nu; 0, S) of the last Update that used pairs (gated or not; see above); 0 before.
  double last_log_likelihood() const;

 private:
  struct Impl;
  explicit KalmanFilter(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace localizer::engine
