#include "engine/attitude/attitude_filter.h"

#include <cmath>
#include <cstdio>
#include <string>

#include "engine/attitude/euler_ekf.h"
#include "engine/attitude/quaternion_ekf.h"

namespace localizer::engine {
namespace {

// Ten significant digits: enough to tell two sample times apart in a message.
std::string FormatDouble(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.10g", value);
  return text;
}

Status CheckPositive(const char* name, double value) {
  if (!std::isfinite(value) || value <= 0.0) {
    return InvalidArgument(std::string(name) + " is " + FormatDouble(value) + ", must be finite and > 0");
  }
  return Status::Ok();
}

Status CheckNonNegative(const char* name, double value) {
  if (!std::isfinite(value) || value < 0.0) {
    return InvalidArgument(std::string(name) + " is " + FormatDouble(value) + ", must be finite and >= 0");
  }
  return Status::Ok();
}

Status CheckFinite(const char* field, const Eigen::Vector3d& v, double t_s) {
  if (v.allFinite()) return Status::Ok();
  return InvalidArgument(std::string("IMU sample at t_s=") + FormatDouble(t_s) + ": " + field + " is not finite (" +
                         FormatDouble(v.x()) + ", " + FormatDouble(v.y()) + ", " + FormatDouble(v.z()) + ")");
}

}  // namespace

StatusOr<AttitudeFilterKind> ParseAttitudeFilterKind(const std::string& name) {
  if (name == "quaternion") return AttitudeFilterKind::kQuaternion;
  if (name == "euler") return AttitudeFilterKind::kEuler;
  return InvalidArgument("attitude filter \"" + name + "\" is unknown (quaternion | euler)");
}

const char* AttitudeFilterKindName(AttitudeFilterKind kind) {
  return kind == AttitudeFilterKind::kEuler ? "euler" : "quaternion";
}

Status AttitudeFilterOptions::Validate() const {
  LOCALIZER_RETURN_IF_ERROR(CheckPositive("gravity_mps2", gravity_mps2));
  LOCALIZER_RETURN_IF_ERROR(CheckPositive("gyro_noise_rps_rthz", gyro_noise_rps_rthz));
  LOCALIZER_RETURN_IF_ERROR(CheckNonNegative("gyro_bias_walk_rps2_rthz", gyro_bias_walk_rps2_rthz));
  LOCALIZER_RETURN_IF_ERROR(CheckNonNegative("gyro_bias_walk_tilt_rps2_rthz", gyro_bias_walk_tilt_rps2_rthz));
  LOCALIZER_RETURN_IF_ERROR(CheckNonNegative("initial_bias_sd_rps", initial_bias_sd_rps));
  LOCALIZER_RETURN_IF_ERROR(CheckPositive("accel_tilt_sd_rad", accel_tilt_sd_rad));
  LOCALIZER_RETURN_IF_ERROR(CheckPositive("accel_reject_mps2", accel_reject_mps2));
  LOCALIZER_RETURN_IF_ERROR(CheckNonNegative("accel_noise_gain", accel_noise_gain));
  LOCALIZER_RETURN_IF_ERROR(CheckNonNegative("accel_lowpass_s", accel_lowpass_s));
  if (!(accel_lowpass_order == 1.0 || accel_lowpass_order == 2.0)) {
    return InvalidArgument("accel_lowpass_order is " + FormatDouble(accel_lowpass_order) + ", must be 1 or 2");
  }
  LOCALIZER_RETURN_IF_ERROR(CheckPositive("mag_heading_sd_rad", mag_heading_sd_rad));
  if (!std::isfinite(mag_declination_rad) || std::abs(mag_declination_rad) > M_PI) {
    return InvalidArgument("mag_declination_rad is " + FormatDouble(mag_declination_rad) +
                           ", must be within [-pi, pi]");
  }
  LOCALIZER_RETURN_IF_ERROR(CheckNonNegative("mag_reference_s", mag_reference_s));
  LOCALIZER_RETURN_IF_ERROR(CheckPositive("mag_norm_tolerance", mag_norm_tolerance));
  LOCALIZER_RETURN_IF_ERROR(CheckPositive("mag_dip_tolerance_rad", mag_dip_tolerance_rad));
  LOCALIZER_RETURN_IF_ERROR(CheckPositive("mag_calibration_s", mag_calibration_s));
  LOCALIZER_RETURN_IF_ERROR(CheckPositive("mag_calibration_diversity", mag_calibration_diversity));
  LOCALIZER_RETURN_IF_ERROR(CheckPositive("mag_calibration_residual", mag_calibration_residual));
  LOCALIZER_RETURN_IF_ERROR(CheckPositive("mag_soft_iron_diversity", mag_soft_iron_diversity));
  if (!std::isfinite(mag_soft_iron_max) || mag_soft_iron_max < 0.0 || mag_soft_iron_max >= 1.0) {
    return InvalidArgument("mag_soft_iron_max is " + FormatDouble(mag_soft_iron_max) + ", must be within [0, 1)");
  }
  LOCALIZER_RETURN_IF_ERROR(CheckPositive("mag_restart_s", mag_restart_s));
  LOCALIZER_RETURN_IF_ERROR(CheckPositive("mag_heading_gate_rad", mag_heading_gate_rad));
  LOCALIZER_RETURN_IF_ERROR(CheckNonNegative("mag_consistency_s", mag_consistency_s));
  LOCALIZER_RETURN_IF_ERROR(CheckNonNegative("mag_consistency_rate_rps", mag_consistency_rate_rps));
  LOCALIZER_RETURN_IF_ERROR(CheckPositive("rest_gyro_rps", rest_gyro_rps));
  LOCALIZER_RETURN_IF_ERROR(CheckPositive("rest_accel_mps2", rest_accel_mps2));
  LOCALIZER_RETURN_IF_ERROR(CheckNonNegative("rest_min_s", rest_min_s));
  LOCALIZER_RETURN_IF_ERROR(CheckPositive("rest_rate_sd_rps", rest_rate_sd_rps));
  return Status::Ok();
}

StatusOr<std::unique_ptr<AttitudeFilter>> CreateAttitudeFilter(const AttitudeFilterOptions& options) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  std::unique_ptr<AttitudeFilter> filter;
  if (options.kind == AttitudeFilterKind::kEuler) {
    filter = std::make_unique<EulerEkf>(options);
  } else {
    filter = std::make_unique<QuaternionEkf>(options);
  }
  return filter;
}

Status ValidateImuSample(const ImuSample& sample, double previous_t_s) {
  // The common case in one test: the checks below build a Status each, which cost about a
  // tenth of a quaternion update (attitude_bench); they run only to name what is wrong.
  if (std::isfinite(sample.t_s) && sample.t_s > previous_t_s && sample.gyro_rps.allFinite() &&
      sample.accel_mps2.allFinite()) {
    return Status::Ok();
  }
  if (!std::isfinite(sample.t_s)) {
    return InvalidArgument("IMU sample t_s is " + FormatDouble(sample.t_s) + ", must be finite");
  }
  if (!(sample.t_s > previous_t_s)) {
    return InvalidArgument("IMU sample t_s=" + FormatDouble(sample.t_s) +
                           " is not after the previous sample's t_s=" + FormatDouble(previous_t_s));
  }
  LOCALIZER_RETURN_IF_ERROR(CheckFinite("gyro_rps", sample.gyro_rps, sample.t_s));
  LOCALIZER_RETURN_IF_ERROR(CheckFinite("accel_mps2", sample.accel_mps2, sample.t_s));
  return Status::Ok();
}

const std::vector<AttitudeNumericOption>& AttitudeNumericOptions() {
  static const std::vector<AttitudeNumericOption> options = {
      {"gravity_mps2", &AttitudeFilterOptions::gravity_mps2},
      {"gyro_noise_rps_rthz", &AttitudeFilterOptions::gyro_noise_rps_rthz},
      {"gyro_bias_walk_rps2_rthz", &AttitudeFilterOptions::gyro_bias_walk_rps2_rthz},
      {"gyro_bias_walk_tilt_rps2_rthz", &AttitudeFilterOptions::gyro_bias_walk_tilt_rps2_rthz},
      {"initial_bias_sd_rps", &AttitudeFilterOptions::initial_bias_sd_rps},
      {"accel_tilt_sd_rad", &AttitudeFilterOptions::accel_tilt_sd_rad},
      {"accel_reject_mps2", &AttitudeFilterOptions::accel_reject_mps2},
      {"accel_noise_gain", &AttitudeFilterOptions::accel_noise_gain},
      {"accel_lowpass_s", &AttitudeFilterOptions::accel_lowpass_s},
      {"accel_lowpass_order", &AttitudeFilterOptions::accel_lowpass_order},
      {"mag_heading_sd_rad", &AttitudeFilterOptions::mag_heading_sd_rad},
      {"mag_declination_rad", &AttitudeFilterOptions::mag_declination_rad},
      {"mag_reference_s", &AttitudeFilterOptions::mag_reference_s},
      {"mag_norm_tolerance", &AttitudeFilterOptions::mag_norm_tolerance},
      {"mag_dip_tolerance_rad", &AttitudeFilterOptions::mag_dip_tolerance_rad},
      {"mag_calibration_s", &AttitudeFilterOptions::mag_calibration_s},
      {"mag_calibration_diversity", &AttitudeFilterOptions::mag_calibration_diversity},
      {"mag_calibration_residual", &AttitudeFilterOptions::mag_calibration_residual},
      {"mag_soft_iron_diversity", &AttitudeFilterOptions::mag_soft_iron_diversity},
      {"mag_soft_iron_max", &AttitudeFilterOptions::mag_soft_iron_max},
      {"mag_restart_s", &AttitudeFilterOptions::mag_restart_s},
      {"mag_heading_gate_rad", &AttitudeFilterOptions::mag_heading_gate_rad},
      {"mag_consistency_s", &AttitudeFilterOptions::mag_consistency_s},
      {"mag_consistency_rate_rps", &AttitudeFilterOptions::mag_consistency_rate_rps},
      {"rest_gyro_rps", &AttitudeFilterOptions::rest_gyro_rps},
      {"rest_accel_mps2", &AttitudeFilterOptions::rest_accel_mps2},
      {"rest_min_s", &AttitudeFilterOptions::rest_min_s},
      {"rest_rate_sd_rps", &AttitudeFilterOptions::rest_rate_sd_rps},
  };
  return options;
}

}  // namespace localizer::engine
