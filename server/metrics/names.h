// Validation of what the Prometheus data model restricts: metric and label names, label
// values, help text and histogram bucket bounds. Registry and Family call these and return
// their statuses; they are public so that callers can check configuration early.
// All functions are pure and thread-safe. Each returns OK or INVALID_ARGUMENT with a
// message naming the offending input.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "engine/core/status.h"

namespace localizer::server::metrics {

// [a-zA-Z_:][a-zA-Z0-9_:]*  (colons are allowed but meant for recording rules).
Status ValidateMetricName(std::string_view name);

// [a-zA-Z_][a-zA-Z0-9_]*, not starting with "__" (reserved for Prometheus' own use).
Status ValidateLabelName(std::string_view name);

// Label names of one family: each valid, no duplicates; histograms may not use "le".
Status ValidateLabelNames(const std::vector<std::string>& names, bool is_histogram);

// Bucket upper bounds: at least one, each finite, strictly increasing. The +Inf bucket is
// implicit and must not be listed.
Status ValidateBucketBounds(const std::vector<double>& upper_bounds);

// Well-formed UTF-8 (the exposition format is UTF-8; label values and help may hold any
// Unicode text). No overlong forms, no surrogates, nothing above U+10FFFF.
bool IsValidUtf8(std::string_view text);

}  // namespace localizer::server::metrics
