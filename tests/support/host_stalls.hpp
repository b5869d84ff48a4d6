#pragma once
// Real-time tests on a host that may stall them. A stall (a gap between ticks beyond the
// servo watchdog) zeroes the force and restarts the safety ramp, as it must; on a loaded
// or throttled host a force-dependent expectation can then miss. Such a test runs its
// attempt again; only a counted stall excuses a failure.

#include <cstdint>
#include <functional>

namespace hattr::test {

/// One attempt of a real-time test: its expectations, and the host stalls its loops counted.
using RealTimeAttempt = std::function<void(std::uint64_t& host_stalls)>;

/// Runs `attempt` until one passes, at most `tries` times. An attempt that fails without a
/// stall fails the test at once with its own messages. When every attempt failed with
/// stalls, the test is reported skipped with the last attempt's failures, never passed.
/// Returns whether an attempt passed.
bool passesUnlessTheHostStalls(const RealTimeAttempt& attempt, int tries = 3);

}  // namespace hattr::test
