#include "server/service/refusal_log.h"

#include "server/service/log.h"

namespace localizer::server {

bool HttpRefusalLog::Note(Clock::time_point now, const std::string& page, int http_code, const char* reason) {
  int64_t unlogged = 0;
  {
    MutexLock lock(&mutex_);
    if (logged_any_ && now - last_ < interval_) {
      ++unlogged_;
      return false;
    }
    logged_any_ = true;
    last_ = now;
    unlogged = unlogged_;
    unlogged_ = 0;
  }
  LogEvent("warn", "auth_refused",
           {{"surface", "http"},
            {"page", page},
            {"code", std::to_string(http_code)},
            {"reason", reason},
            {"unlogged", std::to_string(unlogged)}});
  return true;
}

}  // namespace localizer::server
