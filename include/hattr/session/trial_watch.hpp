#pragma once
/// What ends a real-time trial early, judged from the servo loop's counters as time passes:
/// a latched fault, a device lost for longer than the give-up time, a device clock that stopped
/// calling for as long, or hattr's own loop stuck for a second. runTrial looks every 2 ms while
/// it waits; the studio's live rig looks from its relay thread, so a trial ends on the same
/// failures with the same words wherever it runs.

#include <chrono>
#include <cstdint>
#include <string>

namespace hattr::device {
class Device;
}
namespace hattr::servo {
class ServoLoop;
}

namespace hattr::session {

/// A device (a network link) that stays disconnected this long, or a loop whose clock (a
/// device's own) stops ticking this long, ends the trial; shorter dropouts and stalls zero the
/// force, ramp in again and are counted in the trial's result and metadata.
inline constexpr auto kGiveUpAfter = std::chrono::milliseconds(50);

/// A loop on hattr's own real-time thread that misses ticks was held up (the host descheduled
/// it, an SDK call hung): the loop counts that as a stall, zeroes the force and ramps in
/// again. Only a loop stuck this long ends the trial.
inline constexpr auto kOwnLoopStuckAfter = std::chrono::seconds(1);

/// A device whose clock is simulated and may pause (an emulator in lockstep,
/// Device::pausableClock) ends the trial only when it has not ticked for this long.
inline constexpr auto kPausedClockGiveUpAfter = std::chrono::seconds(60);

/// A watcher that itself woke this late was frozen with the process (a host stall): it saw
/// nothing of that time, so the lost and stopped timers start again instead of blaming the
/// device or the loop for the host's pause (the loop counts the stall itself).
inline constexpr auto kWatcherLate = std::chrono::milliseconds(10);

class TrialWatch {
 public:
  using Clock = std::chrono::steady_clock;

  /// Watches `loop`, which drives `device` (both outlive the watch), from `now` (its start).
  TrialWatch(const servo::ServoLoop& loop, const device::Device& device, Clock::time_point now = Clock::now());

  /// One look at `now` (every few milliseconds, from one thread): why the trial must end now
  /// ("device fault: ...", "device lost: ...", "the device's clock stopped calling the servo
  /// loop", "the servo loop stopped ticking"), or empty while it may go on. runTrial looks
  /// here before it looks at the recorder's end: a failure seen in the same look as the end
  /// wins (before this class, a lost or stopped device came after the end rule there).
  [[nodiscard]] std::string check(Clock::time_point now = Clock::now());

 private:
  const servo::ServoLoop& loop_;
  const device::Device& device_;
  Clock::duration stopped_after_;
  bool lost_ = false;
  Clock::time_point lost_since_{};
  std::uint64_t last_ticks_ = 0;
  Clock::time_point last_tick_seen_;
  Clock::time_point last_wake_;
};

}  // namespace hattr::session
