// The attitude studies' knob: filter options from ATT_OPT="name=value,name=value" over the
// defaults (any numeric option AttitudeNumericOptions names; an unknown name fails the test).
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <map>
#include <string>

#include "engine/attitude/attitude_filter.h"

namespace localizer::engine::testing {

inline AttitudeFilterOptions OptionsFromEnvironment() {
  AttitudeFilterOptions options;
  const char* text = std::getenv("ATT_OPT");
  if (text == nullptr) return options;
  std::map<std::string, double AttitudeFilterOptions::*> fields;
  for (const auto& [name, member] : AttitudeNumericOptions()) fields.emplace(name, member);
  std::string rest = text;
  while (!rest.empty()) {
    const size_t comma = rest.find(',');
    const std::string item = rest.substr(0, comma);
    rest = comma == std::string::npos ? "" : rest.substr(comma + 1);
    const size_t eq = item.find('=');
    const auto it = fields.find(item.substr(0, eq));
    if (eq == std::string::npos || it == fields.end()) {
      ADD_FAILURE() << "ATT_OPT: unknown " << item;
      continue;
    }
    options.*(it->second) = std::atof(item.c_str() + eq + 1);
  }
  return options;
}

}  // namespace localizer::engine::testing
