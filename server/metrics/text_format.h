// The Prometheus text exposition format, version 0.0.4
// (https://prometheus.io/docs/instrumenting/exposition_formats/), written from plain
// MetricFamily values. This is the only serialiser; Registry::Serialize calls it.
//
// For each family, in the order given:
//   # HELP <name> <help, with \ as \\ and newline as \n>
//   # TYPE <name> counter|gauge|histogram
//   <name>{<label>="<value>",...} <number>          one line per series (counter, gauge)
//   <name>_bucket{...,le="<bound>"} <cumulative>     histograms: one per finite bound, then
//   <name>_bucket{...,le="+Inf"} <count>             the +Inf bucket,
//   <name>_sum{...} <sum>                            the sum
//   <name>_count{...} <count>                        and the count
// A series without labels is written without braces. Label values escape \ as \\, " as \"
// and newline as \n. No timestamps are written (Prometheus stamps the scrape). A family
// with no series yet is written as its HELP and TYPE lines only.
//
// All functions are pure and thread-safe.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "server/metrics/metric_family.h"

namespace localizer::server::metrics {

// The Content-Type of what SerializeTextFormat writes.
inline constexpr char kTextFormatContentType[] = "text/plain; version=0.0.4; charset=utf-8";

std::string SerializeTextFormat(const std::vector<MetricFamily>& families);

// A sample value or bucket bound as the format spells it, such that parsing it back gives
// the same double: integers of magnitude below 2^53 as integers ("3", "-12", "1000000");
// other finite values with the fewest digits that round-trip, laid out as Go's
// strconv.FormatFloat(v, 'g', -1, 64) does (as Prometheus' Go client writes `le`): plain
// decimals for decimal exponents -4..5 ("0.1", "0.00025"), exponent form otherwise
// ("2.5e-05", "1.5e+06", "1e+300"); and "+Inf", "-Inf", "NaN".
std::string FormatNumber(double value);

// `text` with \ -> \\, " -> \" and newline -> \n (label values).
std::string EscapeLabelValue(std::string_view text);
// `text` with \ -> \\ and newline -> \n (HELP text).
std::string EscapeHelp(std::string_view text);

}  // namespace localizer::server::metrics
