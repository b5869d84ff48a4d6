#pragma once
/// The servo loop: per tick, read the device → world (paper) forces → guidance forces → the
/// safety path → write the device → publish the sample (SPSC ring for the recorder, triple
/// buffer for the GUI). One tick function, two clocks: a real-time thread at 1–10 kHz, or
/// simulated time as fast as possible and deterministic. See docs/realtime.md.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <string_view>
#include <thread>

#include "hattr/core/histogram.hpp"
#include "hattr/core/pen_state.hpp"
#include "hattr/core/guidance_controller.hpp"
#include "hattr/core/sample.hpp"
#include "hattr/core/spsc_ring.hpp"
#include "hattr/core/triple_buffer.hpp"
#include "hattr/device/device.hpp"
#include "hattr/servo/force_safety.hpp"
#include "hattr/servo/realtime.hpp"

namespace hattr::servo {

struct ServoConfig {
  double rate_hz = 1000.0;                                  ///< 1 to 10 kHz
  RealtimeSettings realtime;                                ///< real-time clock only
  std::chrono::nanoseconds stall_threshold{10'000'000};     ///< watchdog: a longer gap zeroes force
  std::size_t sample_ring_capacity = 1u << 16;              ///< power of two
  std::size_t command_ring_capacity = 64;                   ///< power of two
  SafetyConfig safety;
};

/// A command posted to the servo thread through the lock-free mailbox.
struct ServoCommand {
  enum class Type : std::uint8_t {
    kClearFault,            ///< clear a latched fault; forces ramp in again
    kRestartRamp,           ///< zero and ramp in (e.g. before a trial)
    kSetGuidanceParameter,  ///< forwarded to GuidanceController::setParameter
  };
  Type type = Type::kClearFault;
  int parameter = 0;
  double value = 0.0;
};

enum class TickStatus : std::uint8_t { kRunning, kFaulted, kStalled, kDeviceError };

/// Which clock ran the loop (the statistics say so).
enum class LoopClock : std::uint8_t {
  kNone,       ///< not run yet
  kSimulated,  ///< runSimulated(): simulated time, as fast as possible
  kRealTime,   ///< start() on the loop's own real-time thread
  kDevice,     ///< start() on a device-clocked device: the device calls the tick
};
std::string_view loopClockName(LoopClock clock) noexcept;

/// Counters readable from any thread while the loop runs: the counts only ever go up;
/// `disconnected` is the device's state now.
struct LiveCounters {
  std::atomic<std::uint64_t> ticks{0};            ///< ticks run (published after the tick's sample is in the ring)
  std::atomic<std::uint64_t> overruns{0};         ///< ticks that ended past the next deadline (real time, device clock)
  std::atomic<std::uint64_t> dropped_samples{0};  ///< samples the ring had no room for (its consumer fell behind)
  std::atomic<std::uint64_t> faults{0};           ///< safety faults latched (published after their tick)
  std::atomic<std::uint64_t> stalls{0};           ///< gaps between ticks beyond the stall threshold (zero force, ramp again)
  std::atomic<std::uint64_t> consumer_stalls{0};  ///< ticks with a required consumer stopped taking samples
  std::atomic<std::uint64_t> link_faults{0};  ///< times the device went from connected to disconnected
  std::atomic<std::uint64_t> disconnected_ticks{0};  ///< ticks with the device disconnected (zero force)
  std::atomic<bool> disconnected{false};             ///< the device is disconnected now
};

class ServoLoop {
 public:
  /// Preallocates everything (rings, buffers). Throws InputError for a bad configuration.
  ServoLoop(device::Device& device, ServoConfig config);
  ~ServoLoop();
  ServoLoop(const ServoLoop&) = delete;
  ServoLoop& operator=(const ServoLoop&) = delete;

  /// The world and guidance stages (may be null). Only while the loop is not running.
  void setWorld(WorldRenderer* world) noexcept { world_ = world; }
  void setGuidance(GuidanceController* guidance) noexcept { guidance_ = guidance; }
  /// A consumer the loop depends on (e.g. the recorder): it stores the t_s of the newest
  /// sample it has taken; when that lags the loop by more than the stall threshold, the
  /// loop zeroes the force (counted in consumer_stalls). Null: no such dependency.
  void requireConsumer(const std::atomic<double>* consumer_time_s) noexcept { consumer_time_s_ = consumer_time_s; }

  /// One tick at loop time `now` (since the loop started). Servo thread only: noexcept,
  /// no allocation, no locks.
  TickStatus tick(std::chrono::nanoseconds now) noexcept;

  /// Simulated time: `ticks` ticks, each one period after the last, as fast as possible.
  /// Deterministic for deterministic stages.
  void runSimulated(std::size_t ticks) noexcept;
  /// Simulated time so far.
  [[nodiscard]] std::chrono::nanoseconds simulatedNow() const noexcept { return sim_now_; }
  /// Simulated time: the next tick comes `gap` late, as after a stall of the host (to rehearse
  /// what a study does with a disturbed trial). A gap beyond the stall threshold is a stall.
  void delaySimulated(std::chrono::nanoseconds gap) noexcept { sim_now_ += gap; }

  /// Real time, on the clock the device declares (Device::clocking()): the loop's own
  /// real-time thread (applies the real-time settings there; throws hattr::Error if they are
  /// required and refused), or, for a device-clocked device, the device's thread calling the
  /// tick at its rate (the loop then measures the period between calls and watches for a
  /// device clock that stops: a gap beyond the stall threshold is counted as a stall).
  /// stop() ends either.
  void start();
  void stop();
  /// The clock of the current or last run.
  [[nodiscard]] LoopClock clock() const noexcept { return clock_.load(std::memory_order_acquire); }
  [[nodiscard]] bool running() const noexcept { return running_.load(std::memory_order_acquire); }
  [[nodiscard]] const RealtimeReport& realtimeReport() const noexcept { return realtime_report_; }

  /// Posts a command; false if the mailbox is full, or if another thread is posting at this very
  /// moment (the mailbox is a single-producer ring: a second producer is turned away, never let
  /// race; it retries as it would on a full mailbox). Any thread; never blocks or allocates.
  bool post(const ServoCommand& command) noexcept {
    if (posting_.test_and_set(std::memory_order_acquire)) return false;
    const bool pushed = commands_.tryPush(command);
    posting_.clear(std::memory_order_release);
    return pushed;
  }

  /// Every sample with its tick number, for one consumer (the recorder).
  [[nodiscard]] SpscRing<TickSample>& samples() noexcept { return samples_; }
  /// The newest sample, for one display reader. In simulated time (runSimulated) it is written
  /// on the last tick of each call: the newest sample between calls, without a locked
  /// exchange on every tick of a run that goes as fast as it can.
  [[nodiscard]] TripleBuffer<Sample>& latest() noexcept { return latest_; }
  [[nodiscard]] const LiveCounters& counters() const noexcept { return counters_; }
  /// |period − nominal| and tick compute time (on a real clock: none in simulated time). Read
  /// only while the loop is stopped.
  [[nodiscard]] const DurationHistogram& periodError() const noexcept { return period_error_; }
  [[nodiscard]] const DurationHistogram& tickCompute() const noexcept { return tick_compute_; }
  [[nodiscard]] const ForceSafety& safety() const noexcept { return safety_; }
  [[nodiscard]] std::chrono::nanoseconds period() const noexcept { return period_; }
  [[nodiscard]] const device::Device& device() const noexcept { return device_; }

 private:
  void drainCommands() noexcept;
  /// The device's pen at `now` (the last good one where the read failed); counts a lost link.
  /// Returns whether the device is disconnected; `status` becomes kDeviceError then.
  bool readPen(std::chrono::nanoseconds now, PenState& pen, TickStatus& status) noexcept;
  /// The tick's sample into the ring and the triple buffer, then the tick and fault counts.
  void publish(const PenState& pen, const ContactForces& contact, const Vec3& command, const Vec3& guide) noexcept;
  void runRealtime();
  void startDeviceClock();
  static void deviceTick(void* context, std::chrono::nanoseconds now) noexcept;
  void watchDeviceClock();

  device::Device& device_;
  bool pausable_clock_;  // Device::pausableClock, asked once (not on every tick)
  ServoConfig config_;
  std::chrono::nanoseconds period_;
  ForceSafety safety_;
  WorldRenderer* world_ = nullptr;
  GuidanceController* guidance_ = nullptr;
  const std::atomic<double>* consumer_time_s_ = nullptr;

  SpscRing<TickSample> samples_;
  SpscRing<ServoCommand> commands_;
  std::atomic_flag posting_ = ATOMIC_FLAG_INIT;  ///< held by the thread posting into commands_ (post)
  TripleBuffer<Sample> latest_;
  LiveCounters counters_;
  DurationHistogram period_error_;
  DurationHistogram tick_compute_;

  std::chrono::nanoseconds last_now_{-1};
  std::uint64_t tick_number_ = 0;
  std::chrono::nanoseconds sim_now_{0};
  bool latest_due_ = true;  // whether this tick writes latest_: always, but within runSimulated
  std::atomic<bool> running_{false};
  std::atomic<bool> stop_requested_{false};
  std::thread thread_;
  std::atomic<LoopClock> clock_{LoopClock::kNone};
  bool link_down_ = false;
  PenState last_good_pen_;  // the last reading the device returned kOk for (servo thread)
  // Device clock: the wall time of the last device tick [ns of monotonicNow], for the watchdog.
  std::atomic<std::int64_t> last_device_tick_ns_{0};
  std::chrono::nanoseconds last_device_wall_{-1};
  RealtimeReport realtime_report_;
  std::exception_ptr start_error_;
};

}  // namespace hattr::servo
