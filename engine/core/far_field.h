// When a frame's data bound a source's range (Estimate::far_field, SourceEstimate::position_m).
#pragma once

namespace localizer::engine {

// sigma_r / r above which a frame is far field: a TDOA array fixes 1/r, nearly Gaussian, and
// at sigma_r = r / 3 the 3-sigma interval of 1/r reaches zero, so nothing bounds the range
// from above.
inline constexpr double kFarFieldRangeShare = 1.0 / 3.0;

}  // namespace localizer::engine
