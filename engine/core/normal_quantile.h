// Quantiles of the standard normal distribution, for detection thresholds and chi-square
// bounds (engine/acquisition/presence.h, engine/filters/divergence_monitor.h).
#pragma once

namespace localizer::engine {

// Upper-tail quantile Q^-1(p), p in (0, 0.5] (clamped); accurate to ~1e-12 relative down to
// p = 1e-300 (Newton on log Q).
double NormalUpperQuantile(double p);
// Quantile Phi^-1(p) for p in (0, 1).
double NormalQuantile(double p);

}  // namespace localizer::engine
