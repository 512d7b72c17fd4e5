// Clang thread-safety annotations (https://clang.llvm.org/docs/ThreadSafetyAnalysis.html).
//
// With clang and -Wthread-safety the compiler checks that a member GUARDED_BY(mu) is only
// touched with `mu` held, that a function REQUIRES(mu) is only called with it held and one
// that EXCLUDES(mu) without it. Other compilers see empty macros. libstdc++'s std::mutex
// carries no annotations: guard state with server/sync/mutex.h's Mutex and MutexLock.
// Abseil (included by gRPC's headers) defines GUARDED_BY, PT_GUARDED_BY, ACQUIRED_AFTER,
// ACQUIRED_BEFORE and NO_THREAD_SAFETY_ANALYSIS to the same attributes: whichever header comes
// first defines them.
// The check: docs/DEVELOPMENT.md.
#pragma once

#if defined(__clang__) && !defined(SWIG)
#define LOCALIZER_THREAD_ANNOTATION(x) __attribute__((x))
#else
#define LOCALIZER_THREAD_ANNOTATION(x)
#endif

// A class whose instances are capabilities (a mutex): CAPABILITY("mutex").
#define CAPABILITY(x) LOCALIZER_THREAD_ANNOTATION(capability(x))
// An RAII class that acquires a capability in its constructor and releases it in its destructor.
#define SCOPED_CAPABILITY LOCALIZER_THREAD_ANNOTATION(scoped_lockable)
// The member is read and written only with the capability held.
#ifndef GUARDED_BY
#define GUARDED_BY(x) LOCALIZER_THREAD_ANNOTATION(guarded_by(x))
#endif
// The pointee (not the pointer) is guarded.
#ifndef PT_GUARDED_BY
#define PT_GUARDED_BY(x) LOCALIZER_THREAD_ANNOTATION(pt_guarded_by(x))
#endif
// Lock order: this capability is taken after / before the listed ones.
#ifndef ACQUIRED_AFTER
#define ACQUIRED_AFTER(...) LOCALIZER_THREAD_ANNOTATION(acquired_after(__VA_ARGS__))
#endif
#ifndef ACQUIRED_BEFORE
#define ACQUIRED_BEFORE(...) LOCALIZER_THREAD_ANNOTATION(acquired_before(__VA_ARGS__))
#endif
// The caller must hold the capability (exclusively / shared).
#define REQUIRES(...) LOCALIZER_THREAD_ANNOTATION(requires_capability(__VA_ARGS__))
#define REQUIRES_SHARED(...) LOCALIZER_THREAD_ANNOTATION(requires_shared_capability(__VA_ARGS__))
// The function takes / gives back the capability (held on return / on entry).
#define ACQUIRE(...) LOCALIZER_THREAD_ANNOTATION(acquire_capability(__VA_ARGS__))
#define RELEASE(...) LOCALIZER_THREAD_ANNOTATION(release_capability(__VA_ARGS__))
#define TRY_ACQUIRE(...) LOCALIZER_THREAD_ANNOTATION(try_acquire_capability(__VA_ARGS__))
// The caller must not hold the capability (the function takes it itself).
#define EXCLUDES(...) LOCALIZER_THREAD_ANNOTATION(locks_excluded(__VA_ARGS__))
// Tells the analysis the capability is held here (checked at run time, if at all, elsewhere).
#define ASSERT_CAPABILITY(x) LOCALIZER_THREAD_ANNOTATION(assert_capability(x))
// The function returns a reference to the capability.
#define RETURN_CAPABILITY(x) LOCALIZER_THREAD_ANNOTATION(lock_returned(x))
// Turns the analysis off for one function: say why beside every use.
#ifndef NO_THREAD_SAFETY_ANALYSIS
#define NO_THREAD_SAFETY_ANALYSIS LOCALIZER_THREAD_ANNOTATION(no_thread_safety_analysis)
#endif
