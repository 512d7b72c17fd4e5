// Multiplicative EKF on the unit quaternion with gyro-bias states: the default attitude filter.
//
// Nominal state: q (body -> world, unit) and the gyro bias b (rad/s). Error state (6):
//     q_true = q (x) exp(dtheta / 2),   b_true = b + db,
// dtheta a small rotation in the BODY frame, covariance P (6x6, blocks P_tt, P_tb, P_bb).
//
// Propagation over dt = t_k - t_{k-1}, with the current gyro reading omega_m:
//     omega = omega_m - b,   q <- q (x) exp(omega dt / 2)  (exact for a constant rate),
//     F = [A  -I dt; 0  I],  A = exp(-[omega x] dt) = R(omega dt)^T,
//     P <- F P F^T + diag(sigma_g^2 dt I, Q_b),
//     Q_b = sigma_tilt^2 dt (I - h h^T) + sigma_up^2 dt h h^T      (h = R^T e_up)
// (sigma_g = gyro_noise_rps_rthz, sigma_up = gyro_bias_walk_rps2_rthz, sigma_tilt =
// gyro_bias_walk_tilt_rps2_rthz: the bias about the level axes, which the accelerometer
// observes, may move faster than the one about Up, on which heading coasts), written
// block-wise (no 6x6 product).
//
// Accelerometer (tilt) update, on f = the accelerometer low-passed in the gyro-tracked world
// frame (accel_lowpass_order first-order stages of time constant accel_lowpass_s / order,
// each turned by every step's rotation), when ||f| - g| <= accel_reject_mps2:
//     z = f / |f|,  h = R^T e_up (the third row of R),  H = [[h x]  0],
//     R_meas = sigma_a^2 I,  sigma_a = accel_tilt_sd_rad (1 + accel_noise_gain ||f| - g| / g).
// Only tilt is observed: a body rotation about h leaves h unchanged, so heading is untouched.
//
// Magnetometer. Each reading first feeds the hard-iron fit (hard_iron_estimator.h, solved
// ten times a second) and, from the same sums, the soft-iron fit (soft_iron_estimator.h,
// solved once a second while the hard-iron fit's diversity is enough); the offset o in use
// (0 until a fit finds one) is subtracted and the correction A in use (I until a trusted
// soft-iron fit is adopted) applied, A (m - o), and the corrected field is used for heading
// only when (1) MagReference (mag_reference.h) finds its
// norm and dip at the reference — learnt in the first second, then set by each trusted fit —
// and (2) the heading innovation, low-passed over 0.5 s, is within mag_heading_gate_rad + 3
// sd of the predicted heading (or has stayed outside it for mag_consistency_s of turning
// faster than mag_consistency_rate_rps, with its norm and dip at the reference). Otherwise
// heading coasts on the gyro. When a trusted fit replaces the offset, or a steady
// disagreement is believed, the heading variance is raised to the initial prior, so the
// heading is re-learnt from the corrected field (and the bias about Up is left alone). See
// AttitudeFilterOptions for the rules. The update:
//     m = R m_body,  psi_m = atan2(m_east, m_north),
//     nu = wrap(mag_declination_rad - psi_m),  H = [-e_up^T R  0] = [-h^T  0],
//     R_meas = mag_heading_sd_rad^2.
// H is the derivative with respect to a rotation about the world's Up axis only, and the
// gain's attitude and bias parts are projected onto that axis (K_theta <- h h^T K_theta,
// K_b <- h h^T K_b; P then by the Joseph form, valid for any gain), so the magnetometer can
// turn the estimate and its bias about Up but never tilt it, even through tilt-heading
// correlations in P (a bias pulled off Up would tilt the estimate as the body turns).
//
// Rest update (RestDetector, rest_detector.h): while at rest the true rate is 0, so the
// reading is a measurement of the bias: z = omega_m, H = [0 I], R_meas = rest_rate_sd^2 I.
//
// Every update is the standard K = P H^T S^-1, x <- x (+) K nu (q <- q (x) exp(K_theta nu / 2),
// b <- b + K_b nu), P <- P - K S K^T, symmetrised. The reset Jacobian of the error state
// (I - [dtheta/2 x]) is taken as I: dtheta is a few milliradians per step.
// Cost per update (6 error states, fixed-size Eigen, no heap, no sin/cos/sqrt in the
// rotation-vector exponential below 0.1 rad; the calibration sums add ~60 multiply-adds and
// the correction ~10 per magnetometer sample, plus a 3x3 solve ten times a second and the
// soft-iron fit, a few microseconds, once a second): see BENCHMARKS.md
// (tests/bench/attitude_bench.cc).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "engine/attitude/attitude_filter.h"
#include "engine/attitude/hard_iron_estimator.h"
#include "engine/attitude/mag_reference.h"
#include "engine/attitude/rest_detector.h"
#include "engine/attitude/soft_iron_estimator.h"

namespace localizer::engine {

class QuaternionEkf final : public AttitudeFilter {
 public:
  // `options` must be valid (AttitudeFilterOptions::Validate; CreateAttitudeFilter checks).
  explicit QuaternionEkf(const AttitudeFilterOptions& options);
  QuaternionEkf(const QuaternionEkf&) = delete;
  QuaternionEkf& operator=(const QuaternionEkf&) = delete;

  Status Update(const ImuSample& sample) override;
  AttitudeEstimate estimate() const override;
  AttitudeFilterKind kind() const override { return AttitudeFilterKind::kQuaternion; }

  // The error-state covariance (dtheta in the body frame, then db).
  const Eigen::Matrix<double, 6, 6>& covariance() const { return p_; }
  // The latest hard-iron fit (solved ten times a second while the magnetometer is in use).
  const HardIronFit& hard_iron_fit() const { return last_fit_; }
  // The latest soft-iron fit (solved once a second while the hard-iron fit's rotation
  // diversity is enough and mag_soft_iron_max > 0).
  const SoftIronFit& soft_iron_fit() const { return last_soft_fit_; }

 private:
  using Matrix6d = Eigen::Matrix<double, 6, 6>;
  void Initialise(const ImuSample& sample);
  void Propagate(const Eigen::Vector3d& rate_rps, double dt_s);
  // Applies x <- x (+) dx.
  void Correct(const Eigen::Matrix<double, 6, 1>& dx);
  bool AccelUpdate(const Eigen::Vector3d& accel_mps2, double dt_s);
  // The heading update from the corrected field in the world frame; turning: the
  // bias-corrected rate is at least mag_consistency_rate_rps (only then does a steady
  // disagreement with the gyro count towards being believed); matches_reference: whether its
  // norm and dip agreed with the reference.
  bool MagUpdate(const Eigen::Vector3d& field_world_uT, double t_s, double dt_s, bool turning, bool* matches_reference);
  // Feeds the hard-iron estimator, adopts its fit when trusted, and returns whether the
  // (offset-corrected) sample was used for heading; rate_rps: the bias-corrected gyro.
  bool MagStep(const Eigen::Vector3d& mag_uT, const Eigen::Vector3d& rate_rps, double t_s, double dt_s);
  void AdoptCalibration(const HardIronFit& fit, double t_s);
  // Adopts a trusted soft-iron fit (correction matrix and offset) once two fits in a row
  // agree and it differs from the one in use by enough to turn the heading.
  void AdoptSoftIron(const SoftIronFit& fit);
  // Raises the heading variance to the initial prior and lets the heading re-learn from the
  // corrected field (without the consistency gate until it has converged); restart_sums:
  // the calibration sums restart too (a new offset: what they hold carried the old one).
  void RelearnHeading(bool restart_sums);
  void RestUpdate(const Eigen::Vector3d& gyro_rps);
  void Symmetrise();

  AttitudeFilterOptions options_;
  MagReference mag_reference_;
  HardIronEstimator hard_iron_;
  HardIronFit last_fit_;
  Eigen::Vector3d mag_offset_uT_ = Eigen::Vector3d::Zero();  // subtracted from each reading
  // Soft iron: the correction A applied after the offset (A (m - o)); I until a trusted
  // soft-iron fit is adopted, and again whenever the hard-iron fit adopts a new offset.
  SoftIronFit last_soft_fit_;
  Eigen::Matrix3d mag_correction_ = Eigen::Matrix3d::Identity();
  bool soft_iron_in_use_ = false;
  Eigen::Matrix3d soft_candidate_ = Eigen::Matrix3d::Identity();  // the previous trusted fit's A
  bool soft_candidate_valid_ = false;
  double next_soft_solve_t_s_ = 0.0;
  // An offset has been found and adopted since the start (until then the offset stays 0).
  bool mag_calibrated_ = false;
  double next_solve_t_s_ = 0.0;
  static constexpr double kNoCandidate = -1e300;
  Eigen::Vector3d candidate_uT_ = Eigen::Vector3d::Zero();  // a new offset being confirmed
  double candidate_since_t_s_ = kNoCandidate;
  double match_fraction_ = 1.0;  // recent samples whose norm and dip matched (low-passed)
  bool restart_armed_ = true;
  double innovation_lowpass_rad_ = 0.0;  // heading innovation, low-passed (consistency gate)
  double inconsistent_s_ = 0.0;          // how long it has been outside the gate, while turning
  bool relearning_heading_ = false;      // a new offset or a believed field: no gate until converged
  RestDetector rest_;
  double accel_stage_tau_s_;  // each low-pass stage's time constant: accel_lowpass_s / order
  Eigen::Quaterniond q_ = Eigen::Quaterniond::Identity();
  Eigen::Vector3d bias_rps_ = Eigen::Vector3d::Zero();
  // The accelerometer low-passed in the (gyro-tracked) world frame, held in body axes: the
  // output, and with accel_lowpass_order 2 the first stage that feeds it.
  Eigen::Vector3d accel_lowpass_mps2_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_stage1_mps2_ = Eigen::Vector3d::Zero();
  Matrix6d p_ = Matrix6d::Zero();
  double t_s_ = 0.0;
  bool initialised_ = false;
  bool accel_used_ = false;
  bool mag_used_ = false;
  bool at_rest_ = false;
};

}  // namespace localizer::engine
