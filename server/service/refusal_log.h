// HttpRefusalLog: the HTTP pages' token refusals in the log, without letting a client that
// retries (a scraper or a browser with a wrong token) flood it.
//
// gRPC refusals are logged one line per call (event=auth_refused, localizer_service.cc); the
// operator pages' refusals (401/403 on /sessions and /) go through Note, which writes
//   level=warn event=auth_refused surface=http page=/sessions code=401 reason=missing unlogged=N
// for the first refusal and then at most one line per `interval` (default 1 s), N counting the
// refusals since the previous line that got none. Every refusal is still counted in
// localizer_auth_refusals_total{reason} by the caller. Thread-safe: pages are served by
// several civetweb workers at once.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

#include "server/sync/mutex.h"

namespace localizer::server {

class HttpRefusalLog final {
 public:
  using Clock = std::chrono::steady_clock;
  explicit HttpRefusalLog(Clock::duration interval = std::chrono::seconds(1)) : interval_(interval) {}

  // Notes one refusal at `now`; returns true when it wrote a line.
  bool Note(Clock::time_point now, const std::string& page, int http_code, const char* reason) EXCLUDES(mutex_);

 private:
  const Clock::duration interval_;
  Mutex mutex_;
  bool logged_any_ GUARDED_BY(mutex_) = false;
  Clock::time_point last_ GUARDED_BY(mutex_);
  int64_t unlogged_ GUARDED_BY(mutex_) = 0;
};

}  // namespace localizer::server
