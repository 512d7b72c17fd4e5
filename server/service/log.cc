#include "server/service/log.h"

#include <atomic>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <mutex>

namespace localizer::server {
namespace {

std::atomic<int> g_min_level{1};
std::mutex g_write_mutex;

int LevelRank(std::string_view level) {
  if (level == "debug") return 0;
  if (level == "info") return 1;
  if (level == "warn") return 2;
  return 3;
}

// Quoted when it has spaces, quotes, '=' or any control byte; inside quotes '"' and '\\'
// are escaped, \n \r \t as such and other control bytes as \xHH, so a client string can
// never break a line or forge a field.
void AppendValue(std::string* line, std::string_view value) {
  bool quote = value.empty();
  for (char ch : value) {
    const auto u = static_cast<unsigned char>(ch);
    if (ch == ' ' || ch == '"' || ch == '=' || ch == '\\' || u < 0x20 || u == 0x7f) quote = true;
  }
  if (!quote) {
    line->append(value);
    return;
  }
  line->push_back('"');
  for (char ch : value) {
    const auto u = static_cast<unsigned char>(ch);
    switch (ch) {
      case '"':
        line->append("\\\"");
        continue;
      case '\\':
        line->append("\\\\");
        continue;
      case '\n':
        line->append("\\n");
        continue;
      case '\r':
        line->append("\\r");
        continue;
      case '\t':
        line->append("\\t");
        continue;
      default:
        break;
    }
    if (u < 0x20 || u == 0x7f) {
      char buf[5];
      std::snprintf(buf, sizeof buf, "\\x%02x", u);
      line->append(buf);
      continue;
    }
    line->push_back(ch);
  }
  line->push_back('"');
}

std::string Timestamp() {
  const auto now = std::chrono::system_clock::now();
  const std::time_t secs = std::chrono::system_clock::to_time_t(now);
  const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000;
  std::tm utc{};
  gmtime_r(&secs, &utc);
  char buf[64];
  std::snprintf(buf, sizeof buf, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", utc.tm_year + 1900, utc.tm_mon + 1, utc.tm_mday,
                utc.tm_hour, utc.tm_min, utc.tm_sec, static_cast<int>(ms));
  return buf;
}

}  // namespace

void SetLogLevel(std::string_view level) { g_min_level.store(LevelRank(level)); }

void LogEvent(std::string_view level, std::string_view event, std::initializer_list<LogField> fields) {
  if (LevelRank(level) < g_min_level.load(std::memory_order_relaxed)) return;
  std::string line = "ts=" + Timestamp() + " level=";
  line.append(level);
  line.append(" event=");
  line.append(event);
  for (const LogField& f : fields) {
    line.push_back(' ');
    line.append(f.first);
    line.push_back('=');
    AppendValue(&line, f.second);
  }
  line.push_back('\n');
  std::lock_guard<std::mutex> lock(g_write_mutex);
  std::fwrite(line.data(), 1, line.size(), stderr);
  std::fflush(stderr);
}

}  // namespace localizer::server
