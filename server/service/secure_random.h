// Secrets for the session registry: ids and resume tokens drawn from the operating
// system's CSPRNG (getrandom(2)), never from a seeded engine whose outputs would let a
// client who has seen a few sessions' ids compute the next session's token.
#pragma once

#include <string>

#include "engine/core/status.h"

namespace localizer::server {

// `digits` lowercase hex digits (4 random bits each) from getrandom(2). Blocks only until
// the kernel's pool is initialised (at boot); INTERNAL if the system call fails.
StatusOr<std::string> SecureRandomHex(int digits);

// a == b in time that depends on the lengths only, not on where they differ (a resume token
// compared this way leaks none of its digits through the time a refusal takes).
bool ConstantTimeEquals(const std::string& a, const std::string& b);

}  // namespace localizer::server
