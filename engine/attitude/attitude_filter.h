// Attitude (orientation) of a platform from its IMU: the interface, its options and the
// factory that picks an implementation.
//
// Conventions (engine/core/imu.h, engine/attitude/attitude_math.h): body frame = the IMU's
// axes; world frame = East-North-Up; body_to_world rotates body vectors into the world
// (v_world = q v_body q^-1), written (w, x, y, z) wherever it leaves the engine; Euler
// angles (roll, pitch, yaw) = intrinsic z-y'-x'', R = Rz(yaw) Ry(pitch) Rx(roll); gyro rad/s,
// accelerometer m/s^2 (specific force, +g up at rest), magnetometer µT.
//
// Heading. Gyro + accelerometer alone cannot observe heading: without the magnetometer yaw
// is relative to the heading at the first sample (yaw = 0 there, its std starting at 0 and
// growing with the integrated gyro noise). With use_mag, yaw is measured against magnetic
// North rotated by mag_declination_rad (default 0: the world's North IS magnetic North; set
// the local declination, east positive, to get true North). The quaternion filter also
// estimates a body-fixed hard-iron offset online (a magnet riding on the sensor; it needs the
// sensor to turn), and uses the field only while its norm, dip and heading agree with the
// reference and the gyro; otherwise heading coasts on the gyro (options below).
//
// Implementations (both final, non-copyable; pick with AttitudeFilterOptions::kind):
//   kQuaternion (default) — multiplicative EKF on the unit quaternion with gyro-bias states,
//       engine/attitude/quaternion_ekf.h. Valid at every attitude.
//   kEuler — the seed's 3-state (roll, pitch, yaw) EKF with Euler-rate kinematics,
//       engine/attitude/euler_ekf.h. Singular at pitch = +-90 degrees; kept for comparison.
//
// Contract of Update (both): the first sample initialises (roll, pitch from its
// accelerometer, yaw from its magnetometer when use_mag, else 0); each later one integrates
// its gyro over the time since the previous sample, then corrects. A sample with a non-finite
// time, gyro or accelerometer value, or with t_s not after the previous sample's, returns
// INVALID_ARGUMENT naming the field and leaves the state untouched. A non-finite magnetometer
// is not an error: that sample simply has no magnetometer update. Not thread-safe: one
// filter per stream. No heap allocation per update.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "engine/core/imu.h"
#include "engine/core/status.h"

namespace localizer::engine {

enum class AttitudeFilterKind { kQuaternion, kEuler };
// "quaternion" | "euler"; INVALID_ARGUMENT otherwise.
StatusOr<AttitudeFilterKind> ParseAttitudeFilterKind(const std::string& name);
const char* AttitudeFilterKindName(AttitudeFilterKind kind);

// Every default is the one parameter set validated on the BROAD trials and on the magnetic
// disturbances added to them (tests/attitude/broad_test, mag_disturbance_test; ACCURACY.md
// has the sensitivity of each new default to doubling and halving).
//   field                         default     unit          used by      why this value
//   kind                          kQuaternion               -
//   use_mag                       false                     both
//   gravity_mps2                  9.81        m/s^2         both
//   gyro_noise_rps_rthz           0.003       rad/s/√Hz     both         process noise
//   gyro_bias_walk_rps2_rthz      2e-5        rad/s^2/√Hz   quaternion   the bias about Up:
//                                                                        slow, heading coasts on it
//   gyro_bias_walk_tilt_rps2_rthz 1e-4        rad/s^2/√Hz   quaternion   the bias about the level
//                                                                        axes: the accelerometer sees
//                                                                        it, so it follows the bias
//                                                                        in motion (6D 0.51 -> 0.46)
//   initial_bias_sd_rps           0.01        rad/s         quaternion
//   accel_tilt_sd_rad             0.2         rad           both         per sample
//   accel_reject_mps2             1.5         m/s^2         both
//   accel_noise_gain              4.0         1             both
//   accel_lowpass_s               2.0         s             quaternion   delay of the world-frame
//                                                                        low-pass (both orders)
//   accel_lowpass_order           2           1             quaternion   1 or 2 stages of tau/order:
//                                                                        linear acceleration at
//                                                                        0.5-2 Hz falls with f^-2,
//                                                                        not f^-1 (trial 16 6D
//                                                                        0.58 -> 0.50 deg)
//   mag_heading_sd_rad            0.2         rad           both         per sample
//   mag_declination_rad           0           rad           both
//   mag_reference_s               1.0         s             both
//   mag_norm_tolerance            0.08        1             both         also: the smallest offset
//                                                                        change acted on
//   mag_dip_tolerance_rad         0.07        rad           both
//   mag_calibration_s             20          s             quaternion   memory of the hard-iron fit
//   mag_calibration_diversity     0.1         1             quaternion   rotation needed to trust it
//   mag_calibration_residual      0.1         1             quaternion   misfit allowed, of |field|
//                                                                        (BROAD's noise alone: 0.03)
//   mag_soft_iron_diversity       0.2         1             quaternion   rotation needed to trust the
//                                                                        soft-iron fit (its 5 extra
//                                                                        parameters need more than
//                                                                        the offset's 3)
//   mag_soft_iron_max             0.25        1             quaternion   largest distortion believed
//                                                                        (eigenvalue of A off 1);
//                                                                        0 turns soft iron off
//   mag_restart_s                 1.0         s             quaternion   how fast a changed field
//                                                                        restarts the fit
//   mag_heading_gate_rad          0.05        rad           quaternion   heading-consistency gate
//   mag_consistency_s             10          s             quaternion   a steady field that
//                                                                        disagrees is believed after
//                                                                        (counted while turning)
//   mag_consistency_rate_rps      0.35        rad/s         quaternion   20 deg/s: the turn rate at
//                                                                        which that time counts; a
//                                                                        magnet on the sensor turns
//                                                                        with it, the Earth's field
//                                                                        does not
//   rest_gyro_rps                 0.03        rad/s         quaternion
//   rest_accel_mps2               0.25        m/s^2         quaternion
//   rest_min_s                    0.3         s             quaternion
//   rest_rate_sd_rps              0.02        rad/s         quaternion
struct AttitudeFilterOptions {
  AttitudeFilterKind kind = AttitudeFilterKind::kQuaternion;
  bool use_mag = false;  // correct heading with the magnetometer (heading-only update)

  double gravity_mps2 = 9.81;  // |g|: the accelerometer's norm at rest
  // Gyro white noise as a density: the attitude random walk per sqrt(second).
  double gyro_noise_rps_rthz = 0.003;
  // Gyro bias random walk (quaternion filter's bias states), split by what observes it: the
  // component about the world's Up (only the magnetometer or rest sees it; while the field
  // is untrusted heading coasts on it, so it may change only slowly) and the components
  // about the level axes (the accelerometer sees them: a faster walk lets the bias measured
  // at rest move to the bias in motion, which differs by g-sensitivity and scale errors).
  double gyro_bias_walk_rps2_rthz = 2e-5;
  double gyro_bias_walk_tilt_rps2_rthz = 1e-4;
  double initial_bias_sd_rps = 0.01;  // prior std of each bias component (bias starts at 0)

  // Accelerometer (tilt) update: the direction of the specific force is taken as "up" with
  // this std per sample, inflated by (1 + accel_noise_gain * ||f| - g| / g) so that samples
  // with linear acceleration count less; samples with ||f| - g| > accel_reject_mps2 are not
  // used at all (motion).
  double accel_tilt_sd_rad = 0.2;
  double accel_reject_mps2 = 1.5;
  double accel_noise_gain = 4.0;
  // Quaternion filter: the accelerometer is first low-passed with this time constant in the
  // world frame as the gyro tracks it (each step the filtered vector is turned by the
  // step's rotation, then moved towards the new sample), so linear accelerations that average
  // out over a few seconds cancel while gravity, fixed in the world, passes undelayed.
  // 0: each raw sample is the measurement (as the Euler EKF always does).
  // accel_lowpass_order (1 or 2): the number of such first-order stages in cascade, each with
  // time constant accel_lowpass_s / order, so the delay a slow change sees (accel_lowpass_s)
  // is the same while a linear acceleration at frequency f >> 1 / accel_lowpass_s is
  // attenuated by (2 pi f tau)^-order instead of (2 pi f accel_lowpass_s)^-1: at 1 Hz,
  // 0.025 against 0.08 (a hand-held sensor's translation, BROAD trial 16; VQF low-passes
  // with a second-order filter in the same frame, Laidig & Seel 2023).
  double accel_lowpass_s = 2.0;
  double accel_lowpass_order = 2.0;

  // Magnetometer (heading) update: the azimuth of the field's horizontal part, std per sample.
  double mag_heading_sd_rad = 0.2;
  double mag_declination_rad = 0.0;  // magnetic North's azimuth east of the world's North
  // The field's norm and dip are learnt over the first mag_reference_s seconds of samples
  // with a magnetometer; afterwards a sample whose norm departs from the reference by more
  // than mag_norm_tolerance (a fraction) or whose dip (from the estimated tilt) departs by
  // more than mag_dip_tolerance_rad is disturbed and not used.
  double mag_reference_s = 1.0;
  double mag_norm_tolerance = 0.08;
  double mag_dip_tolerance_rad = 0.07;
  // Hard-iron calibration (quaternion filter; engine/attitude/hard_iron_estimator.h): a
  // body-fixed offset (a magnet riding on the sensor) is fitted over the recent past (time
  // constant mag_calibration_s). The fit is trusted when the rotation diversity (the
  // smallest eigenvalue of the information about the offset per sample, 0..1) is at least
  // mag_calibration_diversity and the RMS misfit at most mag_calibration_residual of the
  // field's norm plus 0.01 of the offset's. A trusted fit sets the norm and dip reference
  // (so a field that changed steadily is re-learnt); it replaces the offset in use when they
  // differ by more than mag_norm_tolerance of the field, the one in use no longer explains
  // the window and the fits have agreed for 2 s; the heading is then re-learnt from the
  // corrected field. When fewer than half the recent samples (time constant mag_restart_s)
  // match the reference, the fit restarts: the field has changed.
  double mag_calibration_s = 20.0;
  double mag_calibration_diversity = 0.1;
  double mag_calibration_residual = 0.1;
  // Soft-iron calibration (quaternion filter; engine/attitude/soft_iron_estimator.h): from the
  // same window, the offset and a symmetric correction A (trace 3) with the corrected field
  // A (m - o), solved once a second while the hard-iron fit's diversity is at least
  // mag_calibration_diversity. Trusted when its own diversity (the smallest information about
  // the distortion, normalised to 1 for attitudes over the whole sphere) is at least
  // mag_soft_iron_diversity, its misfit within the hard-iron fit's allowance and every
  // eigenvalue of A within mag_soft_iron_max of 1. Adopted (correction and offset, the heading
  // re-learnt) when two fits a second apart agree and it changes A by more than 0.01; dropped
  // when the hard-iron fit adopts a new offset. mag_soft_iron_max = 0: hard iron only.
  double mag_soft_iron_diversity = 0.2;
  double mag_soft_iron_max = 0.25;
  double mag_restart_s = 1.0;
  // Consistency with the gyro (quaternion filter): a sample is disturbed when the heading
  // innovation, low-passed over 0.5 s, exceeds mag_heading_gate_rad plus 3 sd of the
  // predicted heading (a field bending near iron turns faster than the gyro says), unless it
  // has done so for mag_consistency_s with its norm and dip at the reference (then the
  // gyro's heading has drifted and the field is believed again: the heading is re-learnt
  // from it, its variance raised to the initial prior). That time counts only over
  // samples whose bias-corrected rate is at least mag_consistency_rate_rps (the idea of
  // VQF's acceptance of a new field, Laidig & Seel 2023): a field that keeps its norm and dip
  // while the sensor turns is fixed in the world, whereas a magnet riding on the sensor turns
  // with it and changes them; without rotation nothing tells the two apart (a 6 µT magnet
  // across the field's horizontal part stays inside the norm and dip gates and turns the
  // heading by 19 deg), so the timer holds and heading keeps coasting. 0: time always counts
  // (the rule before). While the field is untrusted, heading coasts on the gyro and its bias.
  double mag_heading_gate_rad = 0.05;
  double mag_consistency_s = 10.0;
  double mag_consistency_rate_rps = 0.35;

  // Rest detection (quaternion filter): when for rest_min_s every sample has
  // |gyro - bias| < rest_gyro_rps and its accelerometer within rest_accel_mps2 of both g and
  // its recent mean, the platform is taken as still and the gyro reading is used as a
  // measurement of the bias with std rest_rate_sd_rps. 0 for rest_min_s turns this off.
  double rest_gyro_rps = 0.03;
  double rest_accel_mps2 = 0.25;
  double rest_min_s = 0.3;
  double rest_rate_sd_rps = 0.02;

  // INVALID_ARGUMENT naming the first field out of range (noises > 0, tolerances > 0,
  // durations >= 0, all finite).
  Status Validate() const;
};

struct AttitudeEstimate {
  double t_s = 0.0;  // the sample time this estimate describes
  Eigen::Quaterniond body_to_world = Eigen::Quaterniond::Identity();
  Eigen::Vector3d euler_rad = Eigen::Vector3d::Zero();  // (roll, pitch, yaw)
  // First-order std of (roll, pitch, yaw): E P_theta E^T with E the Euler-rate matrix
  // (attitude_math.h); grows without bound for roll and yaw near pitch = +-90 degrees, where
  // those angles are undefined — world_error_sd_rad stays meaningful there.
  Eigen::Vector3d sd_rad = Eigen::Vector3d::Zero();
  // Std of the attitude error as a small rotation about the world's East, North, Up axes
  // (the first two: inclination, the third: heading).
  Eigen::Vector3d world_error_sd_rad = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_bias_rps = Eigen::Vector3d::Zero();  // zero for the Euler EKF
  bool initialised = false;
  // What the last update did (for diagnostics and tests).
  bool accel_used = false;  // false: no update (motion) or not initialised
  bool mag_used = false;    // false: no mag, use_mag off, still learning, or disturbed
  bool at_rest = false;     // rest detected (bias refined)
  // Magnetometer calibration (quaternion filter with use_mag; false and zero otherwise):
  // whether a hard-iron offset has been found and is subtracted from each reading, and that
  // offset (engine/attitude/hard_iron_estimator.h).
  bool mag_calibrated = false;
  Eigen::Vector3d mag_offset_uT = Eigen::Vector3d::Zero();
  // The soft-iron correction A applied after the offset, A (m - o) (symmetric, trace 3;
  // identity until a soft-iron fit is adopted; engine/attitude/soft_iron_estimator.h).
  Eigen::Matrix3d mag_correction = Eigen::Matrix3d::Identity();
};

class AttitudeFilter {
 public:
  virtual ~AttitudeFilter() = default;
  // See the contract above.
  virtual Status Update(const ImuSample& sample) = 0;
  virtual AttitudeEstimate estimate() const = 0;
  virtual AttitudeFilterKind kind() const = 0;
};

// The filter `options.kind` names; INVALID_ARGUMENT when options.Validate() fails.
StatusOr<std::unique_ptr<AttitudeFilter>> CreateAttitudeFilter(const AttitudeFilterOptions& options);

// Every numeric option by its field's name, for callers that set options by name (the
// Python module, studies).
using AttitudeNumericOption = std::pair<const char*, double AttitudeFilterOptions::*>;
const std::vector<AttitudeNumericOption>& AttitudeNumericOptions();

// INVALID_ARGUMENT naming the field when t_s, gyro or accel has a non-finite entry, or when
// t_s is not after previous_t_s (pass -infinity before the first sample).
Status ValidateImuSample(const ImuSample& sample, double previous_t_s);

}  // namespace localizer::engine
