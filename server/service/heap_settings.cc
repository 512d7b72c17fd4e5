#include "server/service/heap_settings.h"

#include <malloc.h>

#include <cstdlib>
#include <cstring>

namespace localizer::server {

bool ConfigureHeapForServing() {
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  if (tunables != nullptr && std::strstr(tunables, "glibc.malloc.") != nullptr) return false;
  // mallopt returns 1 on success; setting the trim threshold also stops glibc adjusting it
  // (and the mmap threshold) dynamically.
  const bool trim = mallopt(M_TRIM_THRESHOLD, static_cast<int>(kTrimThresholdBytes)) == 1;
  const bool pad = mallopt(M_TOP_PAD, static_cast<int>(kTopPadBytes)) == 1;
  return trim && pad;
}

}  // namespace localizer::server
