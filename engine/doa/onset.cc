#include "engine/doa/onset.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace localizer::engine {

Status OnsetOptions::Validate() const {
  if (!std::isfinite(min_rise_db)) return InvalidArgument("min_rise_db must be finite");
  if (!(frame_period_s > 0.0) || !std::isfinite(frame_period_s))
    return InvalidArgument("frame_period_s must be positive");
  if (!(memory_s >= frame_period_s) || memory_s / frame_period_s > 1e4)
    return InvalidArgument("memory_s must be in [frame_period_s, 1e4 frame_period_s]");
  return Status::Ok();
}

OnsetDetector::OnsetDetector(const OnsetOptions& options)
    : options_(options),
      memory_frames_(static_cast<size_t>(std::max(1.0, std::round(options.memory_s / options.frame_period_s)))) {}

StatusOr<OnsetDetector> OnsetDetector::Create(const OnsetOptions& options) {
  LOCALIZER_RETURN_IF_ERROR(options.Validate());
  return OnsetDetector(options);
}

Status OnsetDetector::Push(double band_power) {
  if (!(band_power >= 0.0) || !std::isfinite(band_power)) return InvalidArgument("band_power must be finite and >= 0");
  const double quietest = past_.empty() ? 0.0 : *std::min_element(past_.begin(), past_.end());
  if (quietest > 0.0) {
    rise_db_ = band_power > 0.0 ? 10.0 * std::log10(band_power / quietest) : -std::numeric_limits<double>::infinity();
  } else {
    rise_db_ = band_power > 0.0 ? std::numeric_limits<double>::infinity() : 0.0;
  }
  onset_ = rise_db_ >= options_.min_rise_db;
  past_.push_back(band_power);
  if (past_.size() > memory_frames_) past_.pop_front();
  return Status::Ok();
}

}  // namespace localizer::engine
