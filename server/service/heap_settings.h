// The C library heap's settings for a long-running server (glibc malloc).
//
// Why: under a backlog many sample blocks and gRPC buffers (~64 KiB each) are alive at once,
// allocated on one thread and freed on another. With glibc's defaults the per-thread arenas
// then grow and shrink as the backlog does: new heaps and grown heaps are mprotect calls,
// trimmed ones madvise/munmap, and each takes the process's memory-map lock for writing while
// every page fault needs it for reading. Measured (perf sched, 300 real-time sessions on two
// cores): the two workers spent most of their time blocked in mprotect, both cores were a
// quarter idle, and the backlog never drained (p50 latency rising to seconds) -- a
// metastable overload that a start-up burst set off in about half the runs.
// What: keep freed memory for reuse (trim only above kTrimThresholdBytes of free top) and grow
// an arena by at least kTopPadBytes at a time (address space only: untouched pages are not
// resident), so that the heap settles at its peak instead of following the backlog.
// The price: after a burst the process keeps up to the burst's peak heap resident until
// sessions reuse it; the memory budget (--memory-budget-mib) still bounds what sessions hold.
#pragma once

#include <cstddef>

namespace localizer::server {

inline constexpr size_t kTrimThresholdBytes = size_t{256} << 20;
inline constexpr size_t kTopPadBytes = size_t{64} << 20;

// Applies the settings above, unless the environment already sets glibc.malloc tunables
// (GLIBC_TUNABLES, the operator's choice wins). Returns whether it applied them. Call once,
// before any thread starts.
bool ConfigureHeapForServing();

}  // namespace localizer::server
