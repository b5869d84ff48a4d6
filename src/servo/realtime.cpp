#include "hattr/servo/realtime.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <time.h>

#include <cerrno>
#include <cstring>
#include <thread>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/core/units.hpp"

namespace hattr::servo {

RealtimePolicy parseRealtimePolicy(std::string_view name) {
  if (name == "require") return RealtimePolicy::kRequire;
  if (name == "try") return RealtimePolicy::kTry;
  if (name == "skip") return RealtimePolicy::kSkip;
  throw InputError(fmt::format("real-time policy: expected require, try or skip, got \"{}\"", name));
}

RealtimeReport applyRealtime(const RealtimeSettings& settings) {
  RealtimeReport report;
  if (settings.policy == RealtimePolicy::kSkip) return report;
  const auto note = [&report](std::string text) { report.notes += (report.notes.empty() ? "" : "; ") + text; };

  // Timer slack: wake as close to the deadline as the kernel allows.
  report.timer_slack_minimal = ::prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL) == 0;

  // Lock memory so page faults never stall the loop.
  if (::mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
    report.memory_locked = true;
  } else {
    note(fmt::format("mlockall refused: {}", std::strerror(errno)));
  }

  // SCHED_FIFO for this thread.
  sched_param param{};
  param.sched_priority = settings.fifo_priority;
  const int fifo_error = ::pthread_setschedparam(::pthread_self(), SCHED_FIFO, &param);
  if (fifo_error == 0) {
    report.fifo = true;
  } else {
    note(fmt::format("SCHED_FIFO refused: {}", std::strerror(fifo_error)));
  }

  // Optional CPU pinning.
  if (settings.cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(static_cast<unsigned>(settings.cpu), &set);
    const int pin_error = ::pthread_setaffinity_np(::pthread_self(), sizeof set, &set);
    report.pinned = pin_error == 0;
    if (!report.pinned) note(fmt::format("pinning to CPU {} refused: {}", settings.cpu, std::strerror(pin_error)));
  }

  if (settings.policy == RealtimePolicy::kRequire && !(report.fifo && report.memory_locked)) {
    throw Error(fmt::format("real-time scheduling was required but not granted ({}); run with CAP_SYS_NICE and "
                            "CAP_IPC_LOCK (see docs/realtime.md) or use --realtime try",
                            report.notes));
  }
  return report;
}

std::chrono::nanoseconds monotonicNow() noexcept {
  timespec ts{};
  ::clock_gettime(CLOCK_MONOTONIC, &ts);
  return std::chrono::seconds(ts.tv_sec) + std::chrono::nanoseconds(ts.tv_nsec);
}

void sleepUntil(std::chrono::nanoseconds deadline, std::chrono::nanoseconds spin) noexcept {
  const std::chrono::nanoseconds wake = deadline - spin;
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(wake.count() / 1'000'000'000);
  ts.tv_nsec = static_cast<long>(wake.count() % 1'000'000'000);
  while (::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
  while (spin.count() > 0 && monotonicNow() < deadline) {
  }
}

DurationHistogram measureSleepFloor(double rate_hz, std::chrono::nanoseconds duration, const RealtimeSettings& settings,
                                    RealtimeReport* report) {
  DurationHistogram histogram;
  std::thread thread([&] {
    const RealtimeReport got = applyRealtime(settings);
    if (report) *report = got;
    const auto period = std::chrono::nanoseconds(units::secondsToNanoseconds(1.0 / rate_hz));
    const auto start = monotonicNow();
    auto deadline = start + period;
    auto last = start;
    while (deadline - start < duration) {
      sleepUntil(deadline, settings.final_spin);
      const auto now = monotonicNow();
      histogram.record(std::abs((now - last - period).count()));
      last = now;
      deadline += period;
      if (now > deadline) deadline = now + period;  // never burst to catch up
    }
  });
  thread.join();
  return histogram;
}

}  // namespace hattr::servo
