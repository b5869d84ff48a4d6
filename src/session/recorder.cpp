#include "hattr/session/recorder.hpp"

#include <cmath>

#include <fmt/format.h>

#include "hattr/core/error.hpp"

namespace hattr::session {

Recorder::Recorder(SpscRing<TickSample>& ring, const RecorderConfig& config, ProfileMetadata metadata, RawChannels raw)
    : ring_(ring), config_(config), profile_(std::move(metadata), raw) {
  profile_.metadata().nominal_rate_hz = 1.0 / config.nominal_period_s;
  profile_.reserve(static_cast<std::size_t>(60.0 / config.nominal_period_s));  // a minute without reallocating
}

Recorder::~Recorder() { stopThread(); }

void Recorder::take(const TickSample& item) {
  // Gaps in the tick numbers are samples the ring lost before we could take them (a late
  // tick leaves a gap in time, not in the numbers).
  const Sample& sample = item.sample;
  if (have_tick_ && item.tick > last_tick_ + 1) missed_ += item.tick - last_tick_ - 1;
  have_tick_ = true;
  last_tick_ = item.tick;
  consumer_time_s_.store(sample.t_s, std::memory_order_release);

  // The loop-time window: nothing before it; its end ends the recording.
  const double half_period = 0.5 * config_.nominal_period_s;  // time stamps are not exact multiples
  if (sample.t_s >= config_.window_end_s - half_period) {
    recording_ = false;
    finished_ = true;
    reached_end_.store(true, std::memory_order_release);
    return;
  }
  if (sample.t_s < config_.window_begin_s - half_period) return;

  // Start and stop.
  const bool armed = armed_.load(std::memory_order_acquire) && item.tick < stop_before_tick_.load(std::memory_order_acquire);
  if (config_.trigger == RecordTrigger::kCommand) {
    recording_ = armed && !finished_;
  } else if (!armed) {
    recording_ = false;
  } else if (!recording_ && !finished_ && sample.pen_down) {
    recording_ = true;
  } else if (recording_) {
    pen_up_since_s_ = sample.pen_down ? -1.0 : (pen_up_since_s_ < 0.0 ? sample.t_s : pen_up_since_s_);
    if (pen_up_since_s_ >= 0.0 && sample.t_s - pen_up_since_s_ >= config_.pen_up_stop_s - half_period) {
      recording_ = false;
      finished_ = true;
      // Nothing more is recorded: with an end rule, writing is over here (its own check below
      // would never see this sample).
      if (config_.end_after_pen_up_s > 0.0) writing_over_.store(true, std::memory_order_release);
    }
  }
  if (!recording_) return;

  // Keep it, on the profile's own clock.
  if (profile_.empty()) t_origin_s_ = sample.t_s;
  Sample kept = sample;
  kept.t_s -= t_origin_s_;
  try {
    profile_.append(kept);  // checks finiteness and increasing time
  } catch (const InputError&) {
    ++rejected_;
    return;
  }

  // Writing: from the first pen-down; over once the pen has stayed up long enough.
  last_kept_s_ = kept.t_s;
  if (kept.pen_down) {
    if (writing_begin_s_ < 0.0) writing_begin_s_ = kept.t_s;
    writing_up_since_s_ = -1.0;
  } else if (writing_begin_s_ >= 0.0 && writing_up_since_s_ < 0.0) {
    writing_up_since_s_ = kept.t_s;
  }
  if (config_.end_after_pen_up_s > 0.0 && writing_up_since_s_ >= 0.0 &&
      kept.t_s - writing_up_since_s_ >= config_.end_after_pen_up_s - half_period) {
    recording_ = false;
    finished_ = true;
    writing_over_.store(true, std::memory_order_release);
  }
}

double Recorder::writingEnd_s() const noexcept {
  if (writing_begin_s_ < 0.0) return -1.0;
  return writing_up_since_s_ >= 0.0 ? writing_up_since_s_ : last_kept_s_;
}

std::size_t Recorder::drain() {
  std::size_t count = 0;
  TickSample item;
  while (ring_.tryPop(item)) {
    take(item);
    ++count;
  }
  return count;
}

void Recorder::startThread(std::chrono::microseconds poll) {
  thread_stop_.store(false);
  thread_ = std::thread([this, poll] {
    while (!thread_stop_.load(std::memory_order_acquire)) {
      drain();
      std::this_thread::sleep_for(poll);
    }
    drain();
  });
}

void Recorder::stopThread() {
  thread_stop_.store(true, std::memory_order_release);
  if (thread_.joinable()) thread_.join();
}

HapticProfile Recorder::takeProfile() {
  auto& extra = profile_.metadata().extra;
  extra["t_origin_s"] = fmt::format("{}", t_origin_s_);
  extra["missed_samples"] = fmt::format("{}", missed_);
  extra["rejected_samples"] = fmt::format("{}", rejected_);
  HapticProfile out = std::move(profile_);
  profile_ = HapticProfile(out.metadata(), out.rawChannels());
  return out;
}

void Recorder::reset() {
  stop();
  profile_ = HapticProfile(profile_.metadata(), profile_.rawChannels());
  recording_ = false;
  finished_ = false;
  pen_up_since_s_ = -1.0;
  writing_begin_s_ = -1.0;
  writing_up_since_s_ = -1.0;
  last_kept_s_ = -1.0;
  writing_over_.store(false, std::memory_order_release);
  reached_end_.store(false, std::memory_order_release);
  t_origin_s_ = 0.0;
  missed_ = 0;
  rejected_ = 0;
  // The next recording counts its gaps from its own first tick: the ticks between two
  // recordings (a mentoring lead's sessions) were never part of either.
  have_tick_ = false;
  last_tick_ = 0;
}

}  // namespace hattr::session
