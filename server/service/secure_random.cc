#include "server/service/secure_random.h"

#include <sys/random.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <system_error>
#include <vector>

namespace localizer::server {

StatusOr<std::string> SecureRandomHex(int digits) {
  if (digits <= 0) return InvalidArgument("SecureRandomHex: digits must be positive");
  std::vector<uint8_t> bytes(static_cast<size_t>((digits + 1) / 2));
  size_t filled = 0;
  while (filled < bytes.size()) {
    const ssize_t got = getrandom(bytes.data() + filled, bytes.size() - filled, 0);
    if (got < 0) {
      if (errno == EINTR) continue;
      return Internal(std::string("getrandom failed: ") + std::generic_category().message(errno));
    }
    filled += static_cast<size_t>(got);
  }
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  out.reserve(static_cast<size_t>(digits));
  for (uint8_t b : bytes) {
    out.push_back(kHex[b >> 4]);
    if (static_cast<int>(out.size()) < digits) out.push_back(kHex[b & 15]);
  }
  return out;
}

bool ConstantTimeEquals(const std::string& a, const std::string& b) {
  if (a.size() != b.size()) return false;
  unsigned char diff = 0;
  for (size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i]);
  return diff == 0;
}

}  // namespace localizer::server
