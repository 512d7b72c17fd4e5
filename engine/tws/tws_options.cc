#include "engine/tws/tws_options.h"

#include <cmath>
#include <cstdint>
#include <string>

namespace localizer::engine::tws {
namespace {

Status Bad(const char* field, double value, const char* why) {
  return InvalidArgument(std::string(field) + " is " + std::to_string(value) + ", " + why);
}

Status BadCount(const char* field, int64_t value, const char* why) {
  return InvalidArgument(std::string(field) + " is " + std::to_string(value) + ", " + why);
}

bool PositiveFinite(double v) { return std::isfinite(v) && v > 0.0; }

}  // namespace

Status TwsOptions::Validate() const {
  if (dimensions != 2 && dimensions != 3) return BadCount("dimensions", dimensions, "must be 2 or 3");
  if (!PositiveFinite(noise.range_sigma_m)) return Bad("noise.range_sigma_m", noise.range_sigma_m, "must be > 0");
  if (!PositiveFinite(noise.bearing_sigma_rad) || noise.bearing_sigma_rad > 1.0)
    return Bad("noise.bearing_sigma_rad", noise.bearing_sigma_rad, "must be in (0, 1]");
  if (dimensions == 3 && (!PositiveFinite(noise.elevation_sigma_rad) || noise.elevation_sigma_rad > 1.0))
    return Bad("noise.elevation_sigma_rad", noise.elevation_sigma_rad, "must be in (0, 1]");
  if (!std::isfinite(accel_noise_mps2) || accel_noise_mps2 < 0.0)
    return Bad("accel_noise_mps2", accel_noise_mps2, "must be >= 0");
  if (!(steady_state_tolerance > 0.0 && steady_state_tolerance < 1.0))
    return Bad("steady_state_tolerance", steady_state_tolerance, "must be in (0, 1)");
  if (!(gate_probability > 0.0 && gate_probability < 1.0))
    return Bad("gate_probability", gate_probability, "must be in (0, 1)");
  if (confirm_window < 1 || confirm_window > 32) return BadCount("confirm_window", confirm_window, "must be in 1..32");
  if (confirm_hits < 1 || confirm_hits > confirm_window)
    return BadCount("confirm_hits", confirm_hits, "must be in 1..confirm_window");
  if (max_coast_scans < 1) return BadCount("max_coast_scans", max_coast_scans, "must be >= 1");
  if (!PositiveFinite(max_position_sigma_m)) return Bad("max_position_sigma_m", max_position_sigma_m, "must be > 0");
  if (!PositiveFinite(initial_speed_sigma_mps))
    return Bad("initial_speed_sigma_mps", initial_speed_sigma_mps, "must be > 0");
  if (!PositiveFinite(max_speed_mps)) return Bad("max_speed_mps", max_speed_mps, "must be > 0");
  if (max_tracks < 1) return BadCount("max_tracks", max_tracks, "must be >= 1");
  if (max_initiations_per_scan < 0)
    return BadCount("max_initiations_per_scan", max_initiations_per_scan, "must be >= 0");
  if (resume_misses < 0) return BadCount("resume_misses", resume_misses, "must be >= 0");
  if (!(coast_velocity_decay_s >= 0.0) || !std::isfinite(coast_velocity_decay_s))
    return Bad("coast_velocity_decay_s", coast_velocity_decay_s, "must be finite and >= 0");
  if (max_plots_per_scan < 1) return BadCount("max_plots_per_scan", max_plots_per_scan, "must be >= 1");
  if (gate_search_budget < 1) return BadCount("gate_search_budget", gate_search_budget, "must be >= 1");
  if (max_assignment_cells < 4) return BadCount("max_assignment_cells", max_assignment_cells, "must be >= 4");
  return Status::Ok();
}

}  // namespace localizer::engine::tws
