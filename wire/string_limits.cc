#include "wire/string_limits.h"

#include <cstdio>

namespace localizer::wire {
namespace {

// A printable ASCII byte as itself, any other as \xHH.
void AppendPrintable(unsigned char u, std::string* out) {
  if (u < 0x20 || u >= 0x7f) {
    char buf[5];
    std::snprintf(buf, sizeof buf, "\\x%02x", u);
    *out += buf;
  } else {
    out->push_back(static_cast<char>(u));
  }
}

}  // namespace

std::string Escape(std::string_view value) {
  std::string out;
  out.reserve(value.size());
  for (const char ch : value) {
    const auto u = static_cast<unsigned char>(ch);
    switch (ch) {
      case '\n':
        out += "\\n";
        continue;
      case '\r':
        out += "\\r";
        continue;
      case '\t':
        out += "\\t";
        continue;
      case '\\':
        out += "\\\\";
        continue;
      case '"':
        out += "\\\"";
        continue;
      default:
        break;
    }
    AppendPrintable(u, &out);
  }
  return out;
}

Status NameRefusal(const Status& status) { return {status.code(), EscapeUnprintable(status.message())}; }

std::string EscapeUnprintable(std::string_view message) {
  std::string out;
  out.reserve(message.size());
  for (const char ch : message) {
    const auto u = static_cast<unsigned char>(ch);
    AppendPrintable(u, &out);
  }
  return out;
}

std::string EscapedPrefix(std::string_view value, size_t max_bytes) {
  if (value.size() <= max_bytes) return Escape(value);
  return Escape(value.substr(0, max_bytes)) + "...";
}

Status CheckLength(std::string_view field, std::string_view value, size_t max_bytes) {
  if (value.size() <= max_bytes) return Status::Ok();
  return InvalidArgument(std::string(field) + " is " + std::to_string(value.size()) + " bytes; at most " +
                         std::to_string(max_bytes) + " allowed (starts \"" + EscapedPrefix(value) + "\")");
}

}  // namespace localizer::wire
