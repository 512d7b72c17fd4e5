// Source presence: is there a coherent source in this frame, or only noise?
//
// The statistic is the normalised spatial spectrum (lag_field.h) at the best position a
// search considered: z = sum_p n_p(lag_p) / sqrt(P) over the P usable pairs. At any one
// position, noise alone makes z ~ N(0, 1). A search that picks the best of M distinct
// combinations of lags raises the null's tail to at most M Q(t) (the union bound), so
//     present  <=>  z >= t = Q^-1(false_alarm / M)
// keeps the per-frame false-alarm probability at or below `false_alarm` whatever the
// array, band or frame size (conservative: the combinations are not independent).
// A real source gives z ~ sqrt(P) x peak_snr, tens to hundreds.
#pragma once

#include "engine/core/normal_quantile.h"

namespace localizer::engine {

// t = Q^-1(false_alarm / combinations); combinations >= 1.
double PresenceThreshold(double false_alarm, double combinations);

}  // namespace localizer::engine
