#pragma once
/// Records a haptic profile from the servo loop's sample ring at the full servo rate, off
/// the servo thread: on command, or from the first pen-down to a long pen-up. Counts every
/// sample it missed (gaps in the loop's tick numbers) and every one it had to reject.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <limits>
#include <thread>

#include "hattr/core/haptic_profile.hpp"
#include "hattr/core/spsc_ring.hpp"

namespace hattr::session {

enum class RecordTrigger {
  kCommand,  ///< between start() and stop()
  kPenDown,  ///< armed by start(): from the first pen-down sample until the pen has been up
             ///< for pen_up_stop_s (or stop())
};

struct RecorderConfig {
  RecordTrigger trigger = RecordTrigger::kCommand;
  double nominal_period_s = 1e-3;   ///< the servo period (the profile's nominal rate)
  double pen_up_stop_s = 1.0;       ///< kPenDown: stop after the pen is up this long
  /// > 0: writing is over once the pen has been up this long [s] after writing began (the
  /// recording's first pen-down sample); recording stops with that sample and writingOver()
  /// becomes true. 0: off. Decided per sample, so the same samples give the same end.
  double end_after_pen_up_s = 0.0;
  /// The loop-time window [s] that may be recorded: samples before `window_begin_s` are not
  /// kept, and the first sample at or past `window_end_s` ends the recording (reachedEnd()).
  /// A real-time trial sets it so that its length does not depend on when the threads that
  /// start and stop the recorder are scheduled. Within half a period of each bound.
  double window_begin_s = -std::numeric_limits<double>::infinity();
  double window_end_s = std::numeric_limits<double>::infinity();
};

class Recorder {
 public:
  /// `ring` is the loop's sample ring; the recorder is its only consumer.
  Recorder(SpscRing<TickSample>& ring, const RecorderConfig& config, ProfileMetadata metadata, RawChannels raw = {.tilt = true});
  ~Recorder();
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  /// Start / stop recording (kCommand), or arm / disarm (kPenDown). Any thread.
  void start() noexcept {
    stop_before_tick_.store(std::numeric_limits<std::uint64_t>::max(), std::memory_order_release);
    armed_.store(true, std::memory_order_release);
  }
  void stop() noexcept { armed_.store(false, std::memory_order_release); }
  /// Stops with the loop's tick `tick`: samples of earlier ticks are still kept when they are
  /// taken later (a consumer behind the loop loses nothing the loop recorded before the stop),
  /// none from `tick` on. Any thread.
  void stopBefore(std::uint64_t tick) noexcept { stop_before_tick_.store(tick, std::memory_order_release); }

  /// Takes every sample waiting in the ring. Consumer thread only. Returns how many.
  std::size_t drain();
  /// Drains in a background thread every `poll` until stopThread() (which drains the rest).
  void startThread(std::chrono::microseconds poll = std::chrono::microseconds(500));
  void stopThread();

  /// Loop time of the newest sample taken (for ServoLoop::requireConsumer).
  [[nodiscard]] const std::atomic<double>& consumerTime() const noexcept { return consumer_time_s_; }
  [[nodiscard]] std::uint64_t missed() const noexcept { return missed_; }
  [[nodiscard]] std::uint64_t rejected() const noexcept { return rejected_; }
  [[nodiscard]] bool recording() const noexcept { return recording_; }
  /// True once writing is over (RecorderConfig::end_after_pen_up_s). Any thread.
  [[nodiscard]] bool writingOver() const noexcept { return writing_over_.load(std::memory_order_acquire); }
  /// True once a sample at or past RecorderConfig::window_end_s was taken. Any thread.
  [[nodiscard]] bool reachedEnd() const noexcept { return reached_end_.load(std::memory_order_acquire); }
  /// The profile times [s] of the first pen-down sample recorded and of the last pen-up (the
  /// first pen-up sample after the last pen-down; the last sample's time if the pen was still
  /// down); negative if the pen never went down. After stopThread(), or from the consumer thread.
  [[nodiscard]] double writingBegin_s() const noexcept { return writing_begin_s_; }
  [[nodiscard]] double writingEnd_s() const noexcept;
  [[nodiscard]] const HapticProfile& profile() const noexcept { return profile_; }
  /// The recorded profile, its times starting at 0 (the loop time of its first sample is in
  /// metadata `t_origin_s`), with `missed_samples` and `rejected_samples` in its metadata.
  /// After stopThread(), or from the consumer thread.
  HapticProfile takeProfile();
  /// Forgets the recording, its counts and its writing span, to record anew with start()
  /// (stopped first). After stopThread(), or from the consumer thread.
  void reset();

 private:
  void take(const TickSample& item);

  SpscRing<TickSample>& ring_;
  RecorderConfig config_;
  HapticProfile profile_;
  std::atomic<bool> armed_{false};
  std::atomic<std::uint64_t> stop_before_tick_{std::numeric_limits<std::uint64_t>::max()};
  std::atomic<double> consumer_time_s_{0.0};
  bool recording_ = false;
  bool finished_ = false;       // kPenDown: stopped after a long pen-up
  bool have_tick_ = false;
  std::uint64_t last_tick_ = 0;
  double pen_up_since_s_ = -1.0;
  double writing_begin_s_ = -1.0;   // profile time of the first pen-down sample
  double writing_up_since_s_ = -1.0;  // profile time the pen last went up after writing began
  double last_kept_s_ = -1.0;
  std::atomic<bool> writing_over_{false};
  std::atomic<bool> reached_end_{false};
  double t_origin_s_ = 0.0;
  std::uint64_t missed_ = 0;
  std::uint64_t rejected_ = 0;
  std::atomic<bool> thread_stop_{false};
  std::thread thread_;
};

}  // namespace hattr::session
