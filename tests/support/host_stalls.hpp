#pragma once
// Real-time tests on a host that may stall them. A stall (a gap between ticks beyond the
// servo watchdog) zeroes the force and restarts the safety ramp, as it must; on a loaded
// or throttled host a force-dependent expectation can then miss. Such a test runs its
// attempt again; only a counted stall excuses a failure.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <thread>

namespace hattr::test {

/// One attempt of a real-time test: its expectations, and the host stalls its loops counted.
using RealTimeAttempt = std::function<void(std::uint64_t& host_stalls)>;

/// Runs `attempt` until one passes, at most `tries` times. An attempt that fails without a
/// stall fails the test at once with its own messages. When every attempt failed with
/// stalls, the test is reported skipped with the last attempt's failures, never passed.
/// Returns whether an attempt passed.
bool passesUnlessTheHostStalls(const RealTimeAttempt& attempt, int tries = 3);

/// A floor measured beside a real-time test: a thread of the test's own process that sleeps
/// 1 ms at a time and counts the wake-ups that came more than `gap` late (the host held the
/// process's threads up). On destruction it adds its count to `host_stalls`, so an attempt
/// that returns early from a failed assertion still reports what the host did.
class HostStallWatch {
 public:
  explicit HostStallWatch(std::uint64_t& host_stalls, std::chrono::milliseconds gap = std::chrono::milliseconds(10));
  ~HostStallWatch();
  HostStallWatch(const HostStallWatch&) = delete;
  HostStallWatch& operator=(const HostStallWatch&) = delete;
  /// Late wake-ups so far.
  [[nodiscard]] std::uint64_t stalls() const noexcept { return stalls_.load(); }

 private:
  std::uint64_t& host_stalls_;
  std::atomic<std::uint64_t> stalls_{0};
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace hattr::test
