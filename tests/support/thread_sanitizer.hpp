#pragma once
// Tests whose cost is computation, not threads: ThreadSanitizer slowed them 8-42 times (the DTW
// kernel's vector loads, the sample codec, the simulated trials) and finds nothing the tests it
// still runs would not (docs/architecture.md, "Build and CI in proportion"). Under it they skip
// themselves, saying why and which test runs their threads under it instead.

#include <gtest/gtest.h>

#if defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define HATTR_UNDER_THREAD_SANITIZER 1
#endif
#endif
#if defined(__SANITIZE_THREAD__) || defined(HATTR_UNDER_THREAD_SANITIZER)
#define HATTR_SKIP_UNDER_THREAD_SANITIZER(why) \
  GTEST_SKIP() << "left to the other builds under ThreadSanitizer: " << (why)
#else
#define HATTR_SKIP_UNDER_THREAD_SANITIZER(why) static_cast<void>(0)
#endif

// A test that starts no thread, in its process or in any process it starts (strace measured it:
// scripts/threads-per-test; the release suite's lint:no-thread-marks checks every mark). It has
// no race for ThreadSanitizer to find, so it skips itself there (AddressSanitizer still runs it).
// The mark is the first line of the test's body.
#define HATTR_STARTS_NO_THREAD()                                                                   \
  HATTR_SKIP_UNDER_THREAD_SANITIZER("it starts no thread, nor does any process it starts "         \
                                    "(lint:no-thread-marks checks it)")

// The same for AddressSanitizer, for a test whose cases repeat one path over data: one case
// keeps the path under it, the others skip saying which one runs it.
#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define HATTR_UNDER_ADDRESS_SANITIZER 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) || defined(HATTR_UNDER_ADDRESS_SANITIZER)
#define HATTR_SKIP_UNDER_ADDRESS_SANITIZER(why) \
  GTEST_SKIP() << "left to the release build under AddressSanitizer: " << (why)
#else
#define HATTR_SKIP_UNDER_ADDRESS_SANITIZER(why) static_cast<void>(0)
#endif

namespace hattr::test {

/// Whether this program runs under a sanitizer (address + undefined, or thread). A test that
/// repeats one path over many inputs runs fewer of them there: the sanitizers look for memory
/// and thread errors, which a path shows on its first inputs, and they slow the simulated
/// trials 10-40 times; the release build runs every input (docs/architecture.md).
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__) || defined(HATTR_UNDER_ADDRESS_SANITIZER) || \
    defined(HATTR_UNDER_THREAD_SANITIZER)
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif

/// The glyph of a test's simulated studies where the glyph is not what it tests: the paper's ந
/// in release, the built-in loop under the sanitizers (its expert writes 2.5 s against 4.4 s,
/// so a trial's simulation takes about half as long and its DTW about a third; the same code).
inline constexpr const char* kStudyGlyph = kSanitized ? "loop" : "na";

}  // namespace hattr::test
