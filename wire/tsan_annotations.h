// Happens-before annotations for ThreadSanitizer at the gRPC callback API's boundaries, for the
// server's reactors and the clients' (the load generator's) alike.
//
// Debian's libgrpc is not built with TSan, so TSan does not see the synchronisation that
// gRPC's completion queue provides between the thread that starts an operation (StartRead,
// StartWrite, Finish, a callback unary call: the message buffer and the reactor's state are
// written before) and the thread that runs its reaction (OnReadDone, OnWriteDone, OnDone, the
// call's callback: they are read there). Each such read looks like a data race to TSan.
//
//   TsanRelease(&read_buffer_);   // just before handing the operation to gRPC
//   StartRead(&read_buffer_);
//   ...
//   void OnReadDone(bool ok) {
//     TsanAcquire(&read_buffer_);  // first thing in the matching reaction
//
// tells TSan what gRPC guarantees, and no more: the address names one kind of operation (the
// message it carries, or the reactor for Finish/OnDone), so a race between the read path and
// the write path is still reported. In a reactor's constructor the release goes after the
// Start/Finish instead: gRPC only notes it there and starts it once the reactor is bound.
// Without TSan both compile to nothing. What gRPC's own inlined header code touches before
// our reaction runs cannot be annotated from here; see tests/sanitizers/tsan.supp.
#pragma once

#if defined(__SANITIZE_THREAD__)  // GCC
#define LOCALIZER_TSAN 1
#elif defined(__has_feature)  // clang
#if __has_feature(thread_sanitizer)
#define LOCALIZER_TSAN 1
#endif
#endif

#ifdef LOCALIZER_TSAN
extern "C" {
// From the TSan runtime (<sanitizer/tsan_interface.h>): a release on `addr` happens before
// every later acquire on the same address.
void __tsan_acquire(void* addr);
void __tsan_release(void* addr);
}
#endif

namespace localizer::wire {

// Everything this thread did so far happens before a later TsanAcquire(addr) on any thread.
inline void TsanRelease([[maybe_unused]] const void* addr) {
#ifdef LOCALIZER_TSAN
  __tsan_release(const_cast<void*>(addr));
#endif
}

// Whatever happened before an earlier TsanRelease(addr) happens before what this thread does next.
inline void TsanAcquire([[maybe_unused]] const void* addr) {
#ifdef LOCALIZER_TSAN
  __tsan_acquire(const_cast<void*>(addr));
#endif
}

}  // namespace localizer::wire
