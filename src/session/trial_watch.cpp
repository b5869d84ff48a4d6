#include "hattr/session/trial_watch.hpp"

#include <fmt/format.h>

#include "hattr/device/device.hpp"
#include "hattr/servo/servo_loop.hpp"

namespace hattr::session {

TrialWatch::TrialWatch(const servo::ServoLoop& loop, const device::Device& device, Clock::time_point now)
    : loop_(loop),
      device_(device),
      stopped_after_(device.pausableClock()                        ? std::chrono::duration_cast<Clock::duration>(kPausedClockGiveUpAfter)
                     : loop.clock() == servo::LoopClock::kDevice ? std::chrono::duration_cast<Clock::duration>(kGiveUpAfter)
                                                                 : std::chrono::duration_cast<Clock::duration>(kOwnLoopStuckAfter)),
      last_ticks_(loop.counters().ticks.load()),
      last_tick_seen_(now),
      last_wake_(now) {}

std::string TrialWatch::check(Clock::time_point now) {
  const auto& c = loop_.counters();
  // Frozen with the process: judge only time this watcher was awake for.
  if (now - last_wake_ > kWatcherLate) {
    last_tick_seen_ = now;
    lost_since_ = now;
  }
  last_wake_ = now;
  // A latched fault (the device's reason when it gives one).
  if (c.faults.load() > 0) {
    const std::string reason = device_.faultReason();
    return fmt::format("device fault: {}", reason.empty() ? "the safety path latched a fault" : reason);
  }
  // Lost: disconnected without a break for the give-up time.
  if (!c.disconnected.load()) {
    lost_ = false;
  } else if (!lost_) {
    lost_ = true;
    lost_since_ = now;
  } else if (now - lost_since_ > kGiveUpAfter) {
    const std::string reason = device_.faultReason();
    return fmt::format("device lost: {}", reason.empty() ? "the device disconnected" : reason);
  }
  // Stopped: no tick for the give-up time (the device's clock) or the stuck time (our own).
  if (const std::uint64_t ticks = c.ticks.load(); ticks != last_ticks_) {
    last_ticks_ = ticks;
    last_tick_seen_ = now;
  } else if (now - last_tick_seen_ > stopped_after_) {
    return loop_.clock() == servo::LoopClock::kDevice ? "the device's clock stopped calling the servo loop"
                                                       : "the servo loop stopped ticking";
  }
  return {};
}

}  // namespace hattr::session
