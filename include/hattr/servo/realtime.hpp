#pragma once
/// Real-time scheduling for the servo thread: SCHED_FIFO, mlockall, CPU pinning, minimal
/// timer slack, absolute-deadline sleeps with an optional final spin. See docs/realtime.md.

#include <chrono>
#include <cstdint>
#include <string>
#include <string_view>

#include "hattr/core/histogram.hpp"

namespace hattr::servo {

/// Whether real-time privileges must be had (kRequire: failing is an error), are tried
/// (kTry: the loop runs without them and says so) or are not asked for (kSkip).
enum class RealtimePolicy { kRequire, kTry, kSkip };
/// The policy named "require", "try" or "skip" (as the CLI spells it); InputError otherwise.
RealtimePolicy parseRealtimePolicy(std::string_view name);

struct RealtimeSettings {
  RealtimePolicy policy = RealtimePolicy::kTry;
  int fifo_priority = 80;                      ///< SCHED_FIFO priority (1..99)
  int cpu = -1;                                ///< pin to this CPU (-1: no pinning)
  std::chrono::nanoseconds final_spin{0};      ///< busy-wait this long before each deadline
};

/// What the calling thread actually got.
struct RealtimeReport {
  bool fifo = false;
  bool memory_locked = false;
  bool pinned = false;
  bool timer_slack_minimal = false;
  std::string notes;  ///< why something was not had
};

/// Applies the settings to the calling thread. Throws hattr::Error when the policy is
/// kRequire and SCHED_FIFO or mlockall are refused. Not on the servo path.
RealtimeReport applyRealtime(const RealtimeSettings& settings);

/// CLOCK_MONOTONIC now.
std::chrono::nanoseconds monotonicNow() noexcept;
/// Sleeps until the absolute CLOCK_MONOTONIC deadline, spinning for the final `spin`.
void sleepUntil(std::chrono::nanoseconds deadline, std::chrono::nanoseconds spin) noexcept;

/// The platform's floor: a bare loop that only sleeps to absolute deadlines at `rate_hz`
/// for `duration`, with the same real-time settings; records |period − nominal|.
DurationHistogram measureSleepFloor(double rate_hz, std::chrono::nanoseconds duration, const RealtimeSettings& settings,
                                    RealtimeReport* report = nullptr);

}  // namespace hattr::servo
