// Limits on the strings a client sends, checked at the edge, and the one way a client
// string is quoted back (in a status message or a log line).
//
//   label                                   <= 256 bytes
//   session_id, resume_token                <= 64 bytes (the server issues 32 hex chars)
//   enum-like strings (backend, filter.motion_model, filter.imm_modes, filter.imm_variant,
//   filter.robust, platform.attitude_filter) <= 64 bytes
//
// A refusal names the field and the limit and never echoes the value: at most
// EscapedPrefix (its first 16 bytes, control and non-ASCII bytes escaped).
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

#include "engine/core/status.h"

namespace localizer::wire {

inline constexpr size_t kMaxLabelBytes = 256;
inline constexpr size_t kMaxSessionIdBytes = 64;
inline constexpr size_t kMaxResumeTokenBytes = 64;
inline constexpr size_t kMaxEnumStringBytes = 64;

// `value` with every byte outside printable ASCII (and '\\', '"') escaped: \n \r \t, or \xHH.
std::string Escape(std::string_view value);
// `message` with every byte outside printable ASCII written as \xHH; quotes and backslashes
// stay. For messages that quote a client's string as given (the engine's name parsers do:
// "filter.robust 'x' is not one of: ..."), before they go back to the client or into a log.
std::string EscapeUnprintable(std::string_view message);
// A refusal from one of the engine's name parsers, which quote the name they refuse as the
// client sent it: control and non-ASCII bytes escaped before the message leaves the server.
Status NameRefusal(const Status& status);
// The first `max_bytes` of `value`, escaped, with "..." when cut.
std::string EscapedPrefix(std::string_view value, size_t max_bytes = 16);

// INVALID_ARGUMENT "<field> is N bytes; at most <max> allowed" when too long.
Status CheckLength(std::string_view field, std::string_view value, size_t max_bytes);

}  // namespace localizer::wire
