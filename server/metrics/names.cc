#include "server/metrics/names.h"

#include <cmath>
#include <cstdint>
#include <string>

#include "server/metrics/text_format.h"

namespace localizer::server::metrics {
namespace {

bool IsAsciiLetter(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z'); }
bool IsAsciiDigit(char c) { return c >= '0' && c <= '9'; }

// A name in double quotes, for error messages. (Built by appending: GCC 12 reports a false
// -Wrestrict for `"\"" + std::string(s)`.)
std::string Quoted(std::string_view s) {
  std::string quoted;
  quoted.reserve(s.size() + 2);
  quoted.push_back('"');
  quoted.append(s);
  quoted.push_back('"');
  return quoted;
}

}  // namespace

Status ValidateMetricName(std::string_view name) {
  if (name.empty()) return InvalidArgument("metric name is empty");
  for (size_t i = 0; i < name.size(); ++i) {
    const char c = name[i];
    const bool ok = IsAsciiLetter(c) || c == '_' || c == ':' || (i > 0 && IsAsciiDigit(c));
    if (!ok) {
      return InvalidArgument("metric name " + Quoted(name) + " must match [a-zA-Z_:][a-zA-Z0-9_:]* (bad character at " +
                             std::to_string(i) + ")");
    }
  }
  return Status::Ok();
}

Status ValidateLabelName(std::string_view name) {
  if (name.empty()) return InvalidArgument("label name is empty");
  for (size_t i = 0; i < name.size(); ++i) {
    const char c = name[i];
    const bool ok = IsAsciiLetter(c) || c == '_' || (i > 0 && IsAsciiDigit(c));
    if (!ok) {
      return InvalidArgument("label name " + Quoted(name) + " must match [a-zA-Z_][a-zA-Z0-9_]* (bad character at " +
                             std::to_string(i) + ")");
    }
  }
  if (name.starts_with("__")) {
    return InvalidArgument("label name " + Quoted(name) + " starts with \"__\", which Prometheus reserves");
  }
  return Status::Ok();
}

Status ValidateLabelNames(const std::vector<std::string>& names, bool is_histogram) {
  for (size_t i = 0; i < names.size(); ++i) {
    LOCALIZER_RETURN_IF_ERROR(ValidateLabelName(names[i]));
    if (is_histogram && names[i] == "le") {
      return InvalidArgument("label name \"le\" is reserved for histogram buckets");
    }
    for (size_t j = 0; j < i; ++j) {
      if (names[j] == names[i]) {
        return InvalidArgument("label name " + Quoted(names[i]) + " is listed twice");
      }
    }
  }
  return Status::Ok();
}

Status ValidateBucketBounds(const std::vector<double>& upper_bounds) {
  if (upper_bounds.empty()) {
    return InvalidArgument("a histogram needs at least one finite bucket upper bound");
  }
  for (size_t i = 0; i < upper_bounds.size(); ++i) {
    if (!std::isfinite(upper_bounds[i])) {
      return InvalidArgument("bucket upper bound " + std::to_string(i) + " is " + FormatNumber(upper_bounds[i]) +
                             "; bounds must be finite (the +Inf bucket is implicit)");
    }
    if (i > 0 && !(upper_bounds[i] > upper_bounds[i - 1])) {
      return InvalidArgument("bucket upper bounds must be strictly increasing; bound " + std::to_string(i) + " (" +
                             FormatNumber(upper_bounds[i]) + ") <= bound " + std::to_string(i - 1) + " (" +
                             FormatNumber(upper_bounds[i - 1]) + ")");
    }
  }
  return Status::Ok();
}

bool IsValidUtf8(std::string_view text) {
  size_t i = 0;
  const size_t n = text.size();
  while (i < n) {
    const auto b0 = static_cast<unsigned char>(text[i]);
    if (b0 < 0x80) {
      ++i;
      continue;
    }
    size_t length = 0;
    uint32_t code_point = 0;
    uint32_t minimum = 0;
    if ((b0 & 0xE0) == 0xC0) {
      length = 2;
      code_point = b0 & 0x1Fu;
      minimum = 0x80;
    } else if ((b0 & 0xF0) == 0xE0) {
      length = 3;
      code_point = b0 & 0x0Fu;
      minimum = 0x800;
    } else if ((b0 & 0xF8) == 0xF0) {
      length = 4;
      code_point = b0 & 0x07u;
      minimum = 0x10000;
    } else {
      return false;  // a continuation byte or 0xF8..0xFF where a sequence must start
    }
    if (n - i < length) return false;
    for (size_t k = 1; k < length; ++k) {
      const auto b = static_cast<unsigned char>(text[i + k]);
      if ((b & 0xC0) != 0x80) return false;
      code_point = (code_point << 6) | (b & 0x3Fu);
    }
    if (code_point < minimum || code_point > 0x10FFFF || (code_point >= 0xD800 && code_point <= 0xDFFF)) {
      return false;
    }
    i += length;
  }
  return true;
}

}  // namespace localizer::server::metrics
