// The server's heap settings (server/service/heap_settings.h): applied, freed memory stays
// with the process for reuse instead of being trimmed as soon as it is freed; and an
// operator's own glibc.malloc tunables leave the heap alone.
#include "server/service/heap_settings.h"

#include <gtest/gtest.h>
#include <malloc.h>

#include <cstdlib>
#include <cstring>
#include <vector>

namespace localizer::server {
namespace {

TEST(HeapSettings, OperatorsMallocTunablesWin) {
  ASSERT_EQ(setenv("GLIBC_TUNABLES", "glibc.malloc.arena_max=2", 1), 0);
  EXPECT_FALSE(ConfigureHeapForServing());
  ASSERT_EQ(unsetenv("GLIBC_TUNABLES"), 0);
}

TEST(HeapSettings, FreedBlocksStayForReuse) {
  ASSERT_EQ(unsetenv("GLIBC_TUNABLES"), 0);
  ASSERT_TRUE(ConfigureHeapForServing());
  // 256 blocks of 64 KiB (a sample block's size) allocated and freed on this thread (the
  // main arena): glibc's default would hand the freed top back to the kernel (a trim above
  // 128 KiB), so that the next backlog faults it in again; kept, it is releasable top space.
  constexpr size_t kBlockBytes = size_t{64} << 10;
  std::vector<void*> blocks;
  for (int i = 0; i < 256; ++i) {
    void* b = std::malloc(kBlockBytes);
    ASSERT_NE(b, nullptr);
    std::memset(b, 1, kBlockBytes);
    blocks.push_back(b);
  }
  for (auto it = blocks.rbegin(); it != blocks.rend(); ++it) std::free(*it);
  const struct mallinfo2 info = mallinfo2();
  EXPECT_GE(info.keepcost, 256 * kBlockBytes) << "arena " << info.arena << " bytes, free " << info.fordblks;
}

}  // namespace
}  // namespace localizer::server
