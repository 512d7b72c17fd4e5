#include "engine/acquisition/presence.h"

#include <algorithm>
#include <cmath>

#include "engine/core/normal_quantile.h"

namespace localizer::engine {
double PresenceThreshold(double false_alarm, double combinations) {
  return NormalUpperQuantile(false_alarm / std::max(1.0, combinations));
}

}  // namespace localizer::engine
