#include "engine/attitude/quaternion_ekf.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "engine/attitude/attitude_math.h"

namespace localizer::engine {
namespace {

// Prior std of the tilt taken from one accelerometer sample (which may carry some motion),
// and of the heading taken from one magnetometer sample.
constexpr double kInitialTiltSdRad = 0.1;
constexpr double kInitialHeadingSdRad = 0.2;
// Time constant of the low-passed heading innovation that the consistency gate tests: long
// enough to average the azimuth's noise (degrees per sample), short against a disturbance.
constexpr double kInnovationLowpass_s = 0.5;
// How long the fits must agree on a new offset before it replaces the one in use.
constexpr double kOffsetConfirm_s = 2.0;
// How often the hard-iron fit is solved: its sums change little in a tenth of a second.
constexpr double kSolveEvery_s = 0.1;
// How often the soft-iron fit is solved: it costs a few microseconds and its window is
// mag_calibration_s long, so once a second loses nothing.
constexpr double kSoftSolveEvery_s = 1.0;
// The smallest change of the soft-iron correction acted on (largest entry of the difference):
// 0.01 turns the heading by at most about 0.6 degrees.
constexpr double kSoftIronChange = 0.01;
// Once a correction is in use, the change at which a refinement replaces it: the fit keeps
// improving as the window sees more attitudes, and a refinement turns the heading by a
// fraction of a degree, which needs no re-learning.
constexpr double kSoftIronRefine = 0.003;

// Third row of R(q): R^T e_up, the world's Up seen in the body frame.
Eigen::Vector3d UpInBody(const Eigen::Quaterniond& q) {
  const double w = q.w(), x = q.x(), y = q.y(), z = q.z();
  return {2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)};
}

}  // namespace

QuaternionEkf::QuaternionEkf(const AttitudeFilterOptions& options)
    : options_(options),
      mag_reference_(options.mag_reference_s, options.mag_norm_tolerance, options.mag_dip_tolerance_rad),
      hard_iron_(options.mag_calibration_s, options.mag_calibration_diversity, options.mag_calibration_residual),
      rest_(options.rest_gyro_rps, options.rest_accel_mps2, options.rest_min_s, options.gravity_mps2),
      accel_stage_tau_s_(options.accel_lowpass_s / options.accel_lowpass_order) {}

void QuaternionEkf::Initialise(const ImuSample& sample) {
  const Eigen::Vector2d tilt = TiltFromAccelerometer(sample.accel_mps2);
  double yaw = 0.0;
  const bool mag = options_.use_mag && sample.mag_uT.allFinite();
  if (mag) {  // the heading that puts the field's horizontal part at the declination
    const Eigen::Quaterniond level = QuaternionFromEuler({tilt.x(), tilt.y(), 0.0});
    yaw = AzimuthEastOfNorth(level * sample.mag_uT) - options_.mag_declination_rad;
  }
  q_ = QuaternionFromEuler({tilt.x(), tilt.y(), yaw});
  bias_rps_.setZero();
  accel_lowpass_mps2_ = sample.accel_mps2;
  accel_stage1_mps2_ = sample.accel_mps2;
  // Tilt and heading prior as a world-frame covariance, turned into the body frame.
  const Eigen::Matrix3d r = q_.toRotationMatrix();
  const double heading_sd = mag ? kInitialHeadingSdRad : 0.0;
  const Eigen::Vector3d world_var(kInitialTiltSdRad * kInitialTiltSdRad, kInitialTiltSdRad * kInitialTiltSdRad,
                                  heading_sd * heading_sd);
  p_.setZero();
  p_.topLeftCorner<3, 3>() = r.transpose() * world_var.asDiagonal() * r;
  p_.bottomRightCorner<3, 3>().diagonal().setConstant(options_.initial_bias_sd_rps * options_.initial_bias_sd_rps);
  t_s_ = sample.t_s;
  initialised_ = true;
  accel_used_ = true;
  mag_used_ = mag;
  at_rest_ = false;
  if (mag) (void)mag_reference_.Observe(q_ * sample.mag_uT, sample.t_s);
  next_solve_t_s_ = sample.t_s + kSolveEvery_s;
  next_soft_solve_t_s_ = sample.t_s + kSoftSolveEvery_s;
}

void QuaternionEkf::Propagate(const Eigen::Vector3d& rate_rps, double dt_s) {
  const Eigen::Quaterniond dq = QuaternionFromRotationVector(rate_rps * dt_s);
  q_ = (q_ * dq).normalized();
  const Eigen::Matrix3d a = dq.toRotationMatrix().transpose();
  // A vector fixed in the world, seen from the body, turns by R(omega dt)^T = A.
  accel_lowpass_mps2_ = a * accel_lowpass_mps2_;
  if (options_.accel_lowpass_order > 1.0) accel_stage1_mps2_ = a * accel_stage1_mps2_;
  // F P F^T with F = [A B; 0 I], B = -dt I, written out per 3x3 block.
  const Eigen::Matrix3d ptt = p_.topLeftCorner<3, 3>();
  const Eigen::Matrix3d ptb = p_.topRightCorner<3, 3>();
  const Eigen::Matrix3d pbb = p_.bottomRightCorner<3, 3>();
  const Eigen::Matrix3d new_ptb = a * ptb - dt_s * pbb;
  Eigen::Matrix3d new_ptt = (a * ptt - dt_s * ptb.transpose()) * a.transpose() - dt_s * new_ptb;
  new_ptt.diagonal().array() += options_.gyro_noise_rps_rthz * options_.gyro_noise_rps_rthz * dt_s;
  p_.topLeftCorner<3, 3>() = new_ptt;
  p_.topRightCorner<3, 3>() = new_ptb;
  p_.bottomLeftCorner<3, 3>() = new_ptb.transpose();
  // Bias walk: sigma_tilt^2 dt (I - h h^T) + sigma_up^2 dt h h^T, h the world's Up in the body.
  const Eigen::Vector3d h = UpInBody(q_);
  const double up_var = options_.gyro_bias_walk_rps2_rthz * options_.gyro_bias_walk_rps2_rthz * dt_s;
  const double tilt_var = options_.gyro_bias_walk_tilt_rps2_rthz * options_.gyro_bias_walk_tilt_rps2_rthz * dt_s;
  p_.bottomRightCorner<3, 3>() += (up_var - tilt_var) * h * h.transpose();
  p_.bottomRightCorner<3, 3>().diagonal().array() += tilt_var;
}

void QuaternionEkf::Correct(const Eigen::Matrix<double, 6, 1>& dx) {
  q_ = (q_ * QuaternionFromRotationVector(dx.head<3>())).normalized();
  bias_rps_ += dx.tail<3>();
}

bool QuaternionEkf::AccelUpdate(const Eigen::Vector3d& accel_mps2, double dt_s) {
  if (options_.accel_lowpass_s > 0.0 && options_.accel_lowpass_order > 1.0) {
    // Two stages of half the time constant: the same delay for slow changes, a second-order
    // roll-off for linear accelerations.
    const double alpha = dt_s / (accel_stage_tau_s_ + dt_s);
    accel_stage1_mps2_ += alpha * (accel_mps2 - accel_stage1_mps2_);
    accel_lowpass_mps2_ += alpha * (accel_stage1_mps2_ - accel_lowpass_mps2_);
  } else if (options_.accel_lowpass_s > 0.0) {
    accel_lowpass_mps2_ += (dt_s / (options_.accel_lowpass_s + dt_s)) * (accel_mps2 - accel_lowpass_mps2_);
  } else {
    accel_lowpass_mps2_ = accel_mps2;
  }
  const Eigen::Vector3d& f = accel_lowpass_mps2_;
  const double norm = f.norm();
  const double departure = std::abs(norm - options_.gravity_mps2);
  if (departure > options_.accel_reject_mps2 || norm <= 0.0) return false;
  const double sd = options_.accel_tilt_sd_rad * (1.0 + options_.accel_noise_gain * departure / options_.gravity_mps2);
  const Eigen::Vector3d h = UpInBody(q_);
  const Eigen::Matrix3d hx = Skew(h);
  // P H^T = P.leftCols(3) [h x]^T (6x3); S = [h x] P_tt [h x]^T + sd^2 I.
  const Eigen::Matrix<double, 6, 3> pht = p_.leftCols<3>() * hx.transpose();
  Eigen::Matrix3d s = hx * pht.topRows<3>();
  s.diagonal().array() += sd * sd;
  const Eigen::Matrix3d s_inv = s.inverse();
  const Eigen::Matrix<double, 6, 3> k = pht * s_inv;
  Correct(k * (f / norm - h));
  p_ -= k * pht.transpose();
  return true;
}

bool QuaternionEkf::MagUpdate(const Eigen::Vector3d& field_world, double t_s, double dt_s, bool turning,
                              bool* matches_reference) {
  *matches_reference = mag_reference_.Observe(field_world, t_s);
  if (!*matches_reference) {
    inconsistent_s_ = 0.0;  // "steadily" below means without a break
    return false;
  }
  if (field_world.head<2>().squaredNorm() < 1e-6) return false;  // no horizontal part
  const double nu = WrapAngle(options_.mag_declination_rad - AzimuthEastOfNorth(field_world));
  // H = [-h^T 0]: P H^T = -P.leftCols(3) h, S = H P H^T + r.
  const Eigen::Vector3d h = UpInBody(q_);
  Eigen::Matrix<double, 6, 1> pht = -(p_.leftCols<3>() * h);
  double heading_var = -h.dot(pht.head<3>());
  // Consistency with the gyro: the innovation, low-passed (one sample's azimuth carries
  // degrees of noise), must stay within the gate plus 3 sd of the predicted heading; a field
  // that bends faster than the gyro turns is disturbed. A field that disagrees steadily
  // for mag_consistency_s while its norm and dip stay at the reference is taken as right
  // (the gyro heading has drifted), and used again — but that time counts only while the
  // sensor turns faster than mag_consistency_rate_rps: a field that keeps its norm and dip
  // while the body turns is fixed in the world (Earth-like), whereas a magnet riding on the
  // sensor turns with it and changes both. Without rotation the two are the same thing to the
  // data (a magnet whose field happens to sit inside the gates would be believed after
  // mag_consistency_s and turn the heading), so the timer holds and heading keeps coasting.
  innovation_lowpass_rad_ += (dt_s / (kInnovationLowpass_s + dt_s)) * (nu - innovation_lowpass_rad_);
  const double gate = options_.mag_heading_gate_rad + 3.0 * std::sqrt(heading_var);
  if (relearning_heading_) {  // after a new offset: the gate waits until the heading has converged
    relearning_heading_ = std::abs(innovation_lowpass_rad_) > options_.mag_heading_gate_rad;
    inconsistent_s_ = 0.0;
  } else if (std::abs(innovation_lowpass_rad_) > gate) {
    if (turning) inconsistent_s_ += dt_s;
    if (inconsistent_s_ < options_.mag_consistency_s) return false;
    // Believed: the heading is off by more than its variance said, so that variance is raised
    // and the heading re-learnt from the field, as after a new offset. With the variance as it
    // was, the gain would put much of a large innovation into the bias about Up through the
    // heading-bias covariance built up while coasting (simulated: 19 deg of heading moved that
    // bias by 0.017 rad/s, which turned the heading away again at 1 deg/s).
    RelearnHeading(/*restart_sums=*/false);
    pht = -(p_.leftCols<3>() * h);
    heading_var = -h.dot(pht.head<3>());
  } else {
    inconsistent_s_ = 0.0;
  }
  const double s = heading_var + options_.mag_heading_sd_rad * options_.mag_heading_sd_rad;
  // The Kalman gain with its attitude and bias parts projected on the world's Up axis (h in the
  // body), so the field can only turn the estimate about Up, never tilt it — even through
  // tilt-heading correlations in P, which a large disturbed innovation would otherwise
  // amplify. With this (suboptimal) gain P takes the Joseph form, expanded for one scalar
  // measurement: P <- P - k (PH^T)^T - (PH^T) k^T + s k k^T.
  Eigen::Matrix<double, 6, 1> k = pht / s;
  k.head<3>() = h * h.dot(k.head<3>());
  k.tail<3>() = h * h.dot(k.tail<3>());  // bias too: a bias off Up would tilt as the body turns
  Correct(k * nu);
  p_ += s * k * k.transpose() - k * pht.transpose() - pht * k.transpose();
  return true;
}

void QuaternionEkf::AdoptCalibration(const HardIronFit& fit, double t_s) {
  // A new offset (beyond the norm gate's tolerance from the one in use) only when the one in
  // use no longer explains the window and the fits have agreed on the new one for
  // kOffsetConfirm_s: a fit with little rotation can trade offset for a passing disturbance
  // for a moment. Before any change the offset stays 0: a clean sensor's fit wanders by
  // tenths of a µT, a degree of heading.
  const double tolerance_uT = options_.mag_norm_tolerance * fit.field_world_uT.norm();
  const bool changed = (fit.offset_uT - mag_offset_uT_).norm() > tolerance_uT;
  // With a soft-iron correction in use its own offset stays: the hard-iron fit's offset is
  // biased by the distortion it does not model.
  bool keep = !changed && (!mag_calibrated_ || soft_iron_in_use_);
  if (changed) {
    if (hard_iron_.ResidualWith(mag_offset_uT_) <= hard_iron_.AllowedResidual(fit)) {
      keep = true;
      candidate_since_t_s_ = kNoCandidate;
    } else if (candidate_since_t_s_ == kNoCandidate || (fit.offset_uT - candidate_uT_).norm() > tolerance_uT) {
      keep = true;
      candidate_uT_ = fit.offset_uT;
      candidate_since_t_s_ = t_s;
    } else {
      keep = t_s - candidate_since_t_s_ < kOffsetConfirm_s;
    }
  }
  if (!keep) mag_offset_uT_ = fit.offset_uT;
  // The reference: the world field that best suits the offset in use.
  const Eigen::Vector3d m = keep ? hard_iron_.FieldWith(mag_offset_uT_) : fit.field_world_uT;
  mag_reference_.Set(m.norm(), std::atan2(-m.z(), m.head<2>().norm()));
  if (keep || !changed) return;
  candidate_since_t_s_ = kNoCandidate;
  // The first offset, or the first after the field changed: the heading so far came from a
  // field that carried another offset, or coasted on the gyro, so it is re-learnt from the
  // corrected field. A soft-iron correction belonged to the old offset's iron: dropped until
  // a fit finds the new one.
  mag_calibrated_ = true;
  mag_correction_.setIdentity();
  soft_iron_in_use_ = false;
  soft_candidate_valid_ = false;
  RelearnHeading(/*restart_sums=*/true);
}

void QuaternionEkf::RelearnHeading(bool restart_sums) {
  inconsistent_s_ = 0.0;
  relearning_heading_ = true;
  const Eigen::Vector3d h = UpInBody(q_);
  const double heading_var = h.dot(p_.topLeftCorner<3, 3>() * h);
  const double extra = std::max(0.0, kInitialHeadingSdRad * kInitialHeadingSdRad - heading_var);
  p_.topLeftCorner<3, 3>() += extra * h * h.transpose();
  if (restart_sums) hard_iron_.Reset();
}

void QuaternionEkf::AdoptSoftIron(const SoftIronFit& fit) {
  // Nothing to gain from a first correction that turns the heading by less than
  // kSoftIronChange (a clean sensor's fit wanders by about that), or from a refinement below
  // kSoftIronRefine.
  const double least = soft_iron_in_use_ ? kSoftIronRefine : kSoftIronChange;
  if ((fit.correction - mag_correction_).cwiseAbs().maxCoeff() < least) {
    soft_candidate_valid_ = false;
    return;
  }
  // Two fits in a row (a second apart) must agree: one fit can trade distortion for a
  // passing disturbance for a moment.
  const bool confirmed = soft_candidate_valid_ && (fit.correction - soft_candidate_).cwiseAbs().maxCoeff() < least;
  soft_candidate_ = fit.correction;
  soft_candidate_valid_ = !confirmed;
  if (!confirmed) return;
  const bool first = !soft_iron_in_use_;
  mag_correction_ = fit.correction;
  mag_offset_uT_ = fit.offset_uT;
  mag_calibrated_ = true;
  soft_iron_in_use_ = true;
  candidate_since_t_s_ = kNoCandidate;
  mag_reference_.Set(fit.field_world_uT.norm(),
                     std::atan2(-fit.field_world_uT.z(), fit.field_world_uT.head<2>().norm()));
  // The first correction can turn the heading by degrees: it is re-learnt from the corrected
  // field. Later ones refine it by a fraction of that, which the heading follows as it is.
  // The sums stay either way: the heading moves by about the correction's own turn, a
  // degree or so, which the window forgets.
  if (first) RelearnHeading(/*restart_sums=*/false);
}

bool QuaternionEkf::MagStep(const Eigen::Vector3d& mag_uT, const Eigen::Vector3d& rate_rps, double t_s, double dt_s) {
  // Whether the sensor turns fast enough for the steady-disagreement timer (MagUpdate) to count.
  const bool turning = rate_rps.squaredNorm() >= options_.mag_consistency_rate_rps * options_.mag_consistency_rate_rps;
  const Eigen::Matrix3d r = q_.toRotationMatrix();
  hard_iron_.Add(r, mag_uT, dt_s);
  if (t_s >= next_solve_t_s_) {
    next_solve_t_s_ = t_s + kSolveEvery_s;
    last_fit_ = hard_iron_.Solve(r);
    if (last_fit_.trusted) {
      AdoptCalibration(last_fit_, t_s);
    } else {
      candidate_since_t_s_ = kNoCandidate;
    }
  }
  if (options_.mag_soft_iron_max > 0.0 && t_s >= next_soft_solve_t_s_) {
    next_soft_solve_t_s_ = t_s + kSoftSolveEvery_s;
    // Without the rotations that separate an offset from the world field there is nothing for
    // the larger fit to find either (its diversity has been well below the hard-iron fit's wherever
    // measured: 0.29 against 0.69 tumbling, 0.02 against 0.11 turning about the vertical).
    if (last_fit_.diversity >= options_.mag_calibration_diversity) {
      const SoftIronLimits limits{options_.mag_soft_iron_diversity, options_.mag_calibration_residual,
                                  options_.mag_soft_iron_max};
      last_soft_fit_ = FitSoftIron(hard_iron_.sums(), limits);
      if (last_soft_fit_.trusted) {
        AdoptSoftIron(last_soft_fit_);
      } else {
        soft_candidate_valid_ = false;
      }
    }
  }
  bool matches_reference = false;
  // The correction is the identity until a soft-iron fit is adopted: multiplying by it
  // changes no bit, so it is skipped.
  const Eigen::Vector3d corrected_uT =
      soft_iron_in_use_ ? Eigen::Vector3d(mag_correction_ * (mag_uT - mag_offset_uT_)) : mag_uT - mag_offset_uT_;
  const bool used = MagUpdate(r * corrected_uT, t_s, dt_s, turning, &matches_reference);
  // The fraction of recent samples whose norm and dip match the reference (time constant
  // mag_restart_s). Below one half the field has changed (a magnet arrived, the
  // surroundings changed) and what the fit learnt before no longer describes it: the fit
  // restarts, once, and again only after the field has matched again (above 0.9).
  match_fraction_ += (dt_s / (options_.mag_restart_s + dt_s)) * ((matches_reference ? 1.0 : 0.0) - match_fraction_);
  if (restart_armed_ && match_fraction_ < 0.5) {
    hard_iron_.Reset();
    restart_armed_ = false;
  } else if (!restart_armed_ && match_fraction_ > 0.9) {
    restart_armed_ = true;
  }
  return used;
}

void QuaternionEkf::RestUpdate(const Eigen::Vector3d& gyro_rps) {
  // H = [0 I]: P H^T = P.rightCols(3), S = P_bb + r I.
  const Eigen::Matrix<double, 6, 3> pht = p_.rightCols<3>();
  Eigen::Matrix3d s = pht.bottomRows<3>();
  s.diagonal().array() += options_.rest_rate_sd_rps * options_.rest_rate_sd_rps;
  const Eigen::Matrix<double, 6, 3> k = pht * s.inverse();
  Correct(k * (gyro_rps - bias_rps_));
  p_ -= k * pht.transpose();
}

void QuaternionEkf::Symmetrise() {
  // 0.5 (P + P^T) over one triangle, mirrored: the same numbers (a + b == b + a and
  // 0.5 (a + a) == a), less than half the work.
#pragma GCC unroll 6
  for (int j = 1; j < 6; ++j) {
#pragma GCC unroll 6
    for (int i = 0; i < j; ++i) p_(i, j) = p_(j, i) = 0.5 * (p_(i, j) + p_(j, i));
  }
}

Status QuaternionEkf::Update(const ImuSample& sample) {
  LOCALIZER_RETURN_IF_ERROR(ValidateImuSample(sample, initialised_ ? t_s_ : -std::numeric_limits<double>::infinity()));
  if (!initialised_) {
    Initialise(sample);
    return Status::Ok();
  }
  const double dt_s = sample.t_s - t_s_;
  t_s_ = sample.t_s;
  const Eigen::Vector3d rate_rps = sample.gyro_rps - bias_rps_;
  Propagate(rate_rps, dt_s);
  at_rest_ = rest_.Update(rate_rps, sample.accel_mps2, dt_s);
  if (at_rest_) RestUpdate(sample.gyro_rps);
  accel_used_ = AccelUpdate(sample.accel_mps2, dt_s);
  mag_used_ = options_.use_mag && sample.mag_uT.allFinite() && MagStep(sample.mag_uT, rate_rps, sample.t_s, dt_s);
  Symmetrise();  // once per sample: rounding only, not per update
  return Status::Ok();
}

AttitudeEstimate QuaternionEkf::estimate() const {
  AttitudeEstimate e;
  e.t_s = t_s_;
  e.initialised = initialised_;
  e.body_to_world = q_;
  e.euler_rad = EulerFromQuaternion(q_);
  const Eigen::Matrix3d ptt = p_.topLeftCorner<3, 3>();
  const Eigen::Matrix3d em = EulerRateMatrix(e.euler_rad.x(), e.euler_rad.y());
  e.sd_rad = (em * ptt * em.transpose()).diagonal().cwiseMax(0.0).cwiseSqrt();
  const Eigen::Matrix3d r = q_.toRotationMatrix();
  e.world_error_sd_rad = (r * ptt * r.transpose()).diagonal().cwiseMax(0.0).cwiseSqrt();
  e.gyro_bias_rps = bias_rps_;
  e.accel_used = accel_used_;
  e.mag_used = mag_used_;
  e.at_rest = at_rest_;
  e.mag_calibrated = mag_calibrated_;
  e.mag_offset_uT = mag_offset_uT_;
  e.mag_correction = mag_correction_;
  return e;
}

}  // namespace localizer::engine
