// INVALID_ARGUMENT messages of the simulation stage's option checks: "field is value;
// requirement", the value printed with 9 significant digits. Internal to engine/sim and
// engine/experiments (which builds on sim).
#pragma once

#include <cstdio>
#include <string>

#include "engine/core/status.h"

namespace localizer::engine::sim_detail {

inline std::string Num(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", value);
  return text;
}

inline Status Invalid(const std::string& field, double value, const std::string& requirement) {
  return InvalidArgument(field + " is " + Num(value) + "; " + requirement);
}

}  // namespace localizer::engine::sim_detail
