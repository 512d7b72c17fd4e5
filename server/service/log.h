// Structured log lines on stderr, one event per line in logfmt:
//   ts=2026-11-22T10:00:00.123Z level=info event=session_open session=3f2a... sensors=4
// Values with spaces, quotes or '=' are quoted. Thread-safe (one write per line).
#pragma once

#include <initializer_list>
#include <string>
#include <string_view>
#include <utility>

namespace localizer::server {

using LogField = std::pair<std::string_view, std::string>;

void LogEvent(std::string_view level, std::string_view event, std::initializer_list<LogField> fields = {});

// Silences LogEvent below `level` ("debug" < "info" < "warn" < "error"); default "info".
void SetLogLevel(std::string_view level);

}  // namespace localizer::server
