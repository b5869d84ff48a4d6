#include "core/live_rig.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "hattr/core/error.hpp"

namespace hattr::studio {
namespace {

constexpr std::size_t kRelayCapacity = 1024;                 // power of two
constexpr auto kRelayPoll = std::chrono::microseconds(500);  // as Recorder::startThread

/// The trial set-up of a run, as session::TrialRun builds it.
session::TrialSetup trialSetupOf(const RunSpec& spec, session::Clock clock) {
  session::TrialSetup setup;
  setup.guidance = spec.guidance;
  setup.reference = spec.reference;
  setup.metadata = spec.metadata;
  setup.duration_s = spec.record == RecordMode::kWindow ? spec.duration_s : 1.0;  // only a trial's window ends
  setup.pen_up_end_s = spec.pen_up_end_s;
  setup.settle_s = spec.settle_s;
  setup.clock = clock;
  setup.trigger = spec.record == RecordMode::kPenDown ? session::RecordTrigger::kPenDown : session::RecordTrigger::kCommand;
  setup.live_guidance = spec.live_guidance;
  setup.live_seed = spec.live_seed;
  setup.check_device = spec.check_device;
  return setup;
}

}  // namespace

RunSpec trialRunSpec(const session::TrialSetup& setup, bool follow_during_settle) {
  RunSpec spec;
  spec.guidance = setup.guidance;
  spec.reference = setup.reference;
  spec.metadata = setup.metadata;
  spec.record = setup.trigger == session::RecordTrigger::kPenDown ? RecordMode::kPenDown : RecordMode::kWindow;
  spec.settle_s = setup.settle_s;
  spec.duration_s = setup.duration_s;
  spec.pen_up_end_s = setup.pen_up_end_s;
  spec.follow_during_settle = follow_during_settle;
  spec.live_guidance = setup.live_guidance;
  spec.live_seed = setup.live_seed;
  spec.check_device = setup.check_device;
  return spec;
}

LiveRig::LiveRig() = default;

LiveRig::~LiveRig() { (void)finish(); }

void LiveRig::start(session::TrialEnvironment& environment, const RunSpec& spec, device::HandScript& hand,
                    session::Clock clock) {
  if (active()) (void)finish();
  HATTR_THROW_UNLESS(std::isfinite(spec.pen_up_stop_s) && spec.pen_up_stop_s > 0.0,
                     "pen-up stop time: expected > 0 s, got {}", spec.pen_up_stop_s);
  // The trial's pipeline, built by the library as runTrial builds it (a mentored mode's
  // settle lengthened to the mentor's minimum).
  auto run = std::make_unique<session::TrialRun>(environment, trialSetupOf(spec, clock), hand,
                                                 spec.follow_during_settle);
  spec_ = spec;
  spec_.settle_s = run->settle_s();
  clock_ = run->clock();

  // The recorder takes samples through a relay ring, so a trial's window starts and ends
  // at exact ticks whatever the clock; it decides the end rule itself, as in runTrial.
  auto relay = std::make_unique<SpscRing<TickSample>>(kRelayCapacity);
  session::RecorderConfig recorder_config = run->recorderConfig();
  if (spec.pen_up_end_s <= 0.0) recorder_config.pen_up_stop_s = spec.pen_up_stop_s;
  auto recorder = std::make_unique<session::Recorder>(*relay, recorder_config, run->metadata());

  environment_ = &environment;
  run_ = std::move(run);
  relay_ = std::move(relay);
  recorder_ = std::move(recorder);
  const double half_period_s = 0.5 / environment.rate_hz();  // time stamps are not exact multiples
  window_begin_s_ = spec_.settle_s - half_period_s;
  window_end_s_ = spec_.settle_s + spec_.duration_s - half_period_s;
  period_s_ = 1.0 / environment.rate_hz();
  window_armed_ = false;
  was_recording_ = false;
  stop_taken_ = false;
  mentor_failure_.clear();
  mentor_checked_ = false;
  watch_.reset();
  failure_.clear();
  failure_tick_ = std::numeric_limits<std::uint64_t>::max();
  stop_.reset();
  status_recording_ = false;
  status_window_done_ = false;
  status_pen_down_done_ = false;
  status_writing_over_ = false;
  status_stopped_ = false;
  status_failed_ = false;
  status_recorded_ = 0;
  status_loop_time_s_ = 0.0;
  if (spec.record == RecordMode::kPenDown) recorder_->start();  // armed; records from the first pen-down

  if (clock_ == session::Clock::kRealTime) {
    run_->loop().requireConsumer(&recorder_->consumerTime());
    relay_stop_.store(false);
    relay_thread_ = std::thread([this] {
      while (!relay_stop_.load(std::memory_order_acquire)) {
        watchTrial();  // before the pump: a failure's last tick is set before its samples are taken
        pump();
        std::this_thread::sleep_for(kRelayPoll);
      }
      pump();
    });
    try {
      run_->loop().start();
    } catch (...) {
      (void)finish();
      throw;
    }
  }
}

void LiveRig::advanceSimulated(double seconds) {
  HATTR_DEMAND(run_ && clock_ == session::Clock::kSimulated, "advanceSimulated() needs a simulated run");
  using session::kSimulatedChunk;
  const auto ticks = static_cast<std::size_t>(std::llround(seconds * environment_->rate_hz()));
  const auto settle_ticks = static_cast<std::uint64_t>(std::llround(spec_.settle_s * environment_->rate_hz()));
  // As runTrial: a trial's loop stops with the chunk in which its window ended; a mentored
  // trial's chunks also stop at the settle's last tick, where runTrial asks for the mentor.
  for (std::size_t done = 0; done < ticks && !status_window_done_.load(std::memory_order_acquire);) {
    std::size_t chunk = std::min(kSimulatedChunk, ticks - done);
    const std::uint64_t ran = run_->loop().counters().ticks.load();
    if (run_->live() && !mentor_checked_ && ran < settle_ticks) chunk = std::min<std::size_t>(chunk, settle_ticks - ran);
    run_->loop().runSimulated(chunk);
    done += chunk;
    pump();
    if (run_->live() && !mentor_checked_ && run_->loop().counters().ticks.load() == settle_ticks) checkMentor();
  }
}

// Loop ring → relay → recorder. A trial's window arms and disarms the recorder at the
// exact sample, the recorder having taken everything before it; a stop request disarms it
// for good at the first sample taken after it, and a failure at the first of its tick on.
void LiveRig::pump() {
  TickSample item;
  while (run_->loop().samples().tryPop(item)) {
    if (!stop_taken_ && (stop_.requested() || item.tick >= failure_tick_)) takeStop();
    if (spec_.record == RecordMode::kWindow && !stop_taken_) {
      const bool in_window = item.sample.t_s >= window_begin_s_ && item.sample.t_s < window_end_s_;
      // As runTrial: a mentor not there when the settle ends fails the trial, nothing recorded.
      if (in_window && !window_armed_ && run_->live() && !mentor_checked_) checkMentor();  // (real time)
      if (!stop_taken_ && in_window != window_armed_) {
        recorder_->drain();
        if (in_window) {
          recorder_->start();
        } else {
          recorder_->stop();
        }
        window_armed_ = in_window;
      }
      // Done with the window's last nominal tick (the next would be past it).
      if (item.sample.t_s >= window_end_s_ - period_s_) status_window_done_.store(true, std::memory_order_release);
    }
    if (!relay_->tryPush(item)) {
      recorder_->drain();
      (void)relay_->tryPush(item);
    }
    status_loop_time_s_.store(item.sample.t_s, std::memory_order_relaxed);
  }
  if (!stop_taken_ && stop_.requested()) takeStop();
  recorder_->drain();
  publishStatus();
}

// What ends a real-time trial early, judged as runTrial judges it (session::TrialWatch, from
// the moment the loop runs). The failure's tick is the loop's count when it is seen: the relay
// takes every sample before it through the window as usual (however far behind the loop it is),
// and stops the recording at the first sample from it on (pump).
void LiveRig::watchTrial() {
  if (spec_.record != RecordMode::kWindow || stop_taken_ || !failure_.empty() ||
      status_window_done_.load(std::memory_order_acquire)) {
    return;
  }
  if (!watch_) {
    if (run_->loop().running()) watch_ = std::make_unique<session::TrialWatch>(run_->loop(), run_->device());
    return;
  }
  std::string failure = watch_->check();
  if (failure.empty()) return;
  failure_tick_ = run_->loop().counters().ticks.load(std::memory_order_acquire);
  failure_ = std::move(failure);
  status_failed_.store(true, std::memory_order_release);
  status_window_done_.store(true, std::memory_order_release);
}

std::optional<Vec3> LiveRig::referenceCue() const noexcept {
  if (!run_ || !spec_.reference || run_->live() != nullptr) return std::nullopt;
  const double index = run_->guidance().cueIndex();
  if (index < 0.0) return std::nullopt;
  return spec_.reference->at(index).p_WT;
}

void LiveRig::checkMentor() {
  mentor_failure_ = run_->mentorUnavailable();
  mentor_checked_ = true;
  if (!mentor_failure_.empty()) {
    takeStop();
    status_failed_.store(true, std::memory_order_release);
    status_window_done_.store(true, std::memory_order_release);
  }
}

void LiveRig::takeStop() {
  recorder_->drain();  // what came before the request is the trial's
  recorder_->stop();
  window_armed_ = false;
  stop_taken_ = true;
}

void LiveRig::publishStatus() {
  // The end rule: the recorder stopped with the sample that ended the trial.
  if (recorder_->writingOver()) {
    status_writing_over_.store(true, std::memory_order_release);
    if (spec_.record == RecordMode::kWindow) status_window_done_.store(true, std::memory_order_release);
  }
  // Stopped by a request; a failure's stop is the failure's.
  status_stopped_.store(stop_taken_ && failure_.empty() && mentor_failure_.empty(), std::memory_order_release);
  const bool recording = recorder_->recording();
  if (spec_.record == RecordMode::kPenDown && was_recording_ && !recording) {
    status_pen_down_done_.store(true, std::memory_order_release);
  }
  was_recording_ = was_recording_ || recording;
  status_recording_.store(recording, std::memory_order_relaxed);
  status_recorded_.store(recorder_->profile().size(), std::memory_order_relaxed);
}

session::TrialResult LiveRig::finish() {
  session::TrialResult result;
  if (!run_) return result;
  if (clock_ == session::Clock::kRealTime) {
    run_->loop().stop();
    relay_stop_.store(true, std::memory_order_release);
    if (relay_thread_.joinable()) relay_thread_.join();
  } else {
    pump();
  }
  recorder_->stop();
  // The result as runTrial reports it; a failure's end reason comes first.
  result = run_->finish(*recorder_, !mentor_failure_.empty() ? mentor_failure_ : failure_, stop_taken_);

  // Tear down in dependency order: the recorder reads the relay, the run's loop drives its device.
  watch_.reset();
  recorder_.reset();
  relay_.reset();
  run_.reset();
  environment_ = nullptr;
  return result;
}

void LiveRig::armRecording() noexcept {
  if (recorder_) recorder_->start();
}

void LiveRig::disarmRecording() noexcept {
  if (recorder_) recorder_->stop();
}

bool LiveRig::readLatest(Sample& out) noexcept { return run_ ? run_->loop().latest().read(out) : false; }

bool LiveRig::post(const servo::ServoCommand& command) noexcept { return run_ ? run_->loop().post(command) : false; }

bool LiveRig::switchMode(guidance::TrainingMode mode) noexcept {
  return post(servo::ServoCommand{.type = servo::ServoCommand::Type::kSetGuidanceParameter,
                                  .parameter = guidance::kParameterMode,
                                  .value = static_cast<double>(static_cast<int>(mode))});
}

RigStatus LiveRig::status() const noexcept {
  RigStatus status;
  if (!run_) return status;
  status.running = clock_ == session::Clock::kSimulated || run_->loop().running();
  status.loop_time_s = status_loop_time_s_.load(std::memory_order_relaxed);
  status.settling = status.loop_time_s < spec_.settle_s;
  status.recording = status_recording_.load(std::memory_order_relaxed);
  status.window_done = status_window_done_.load(std::memory_order_acquire);
  status.pen_down_done = status_pen_down_done_.load(std::memory_order_acquire);
  status.writing_over = status_writing_over_.load(std::memory_order_acquire);
  status.stopped = status_stopped_.load(std::memory_order_acquire);
  status.failed = status_failed_.load(std::memory_order_acquire);
  status.recorded_samples = status_recorded_.load(std::memory_order_relaxed);
  return status;
}

const servo::LiveCounters* LiveRig::counters() const noexcept { return run_ ? &run_->loop().counters() : nullptr; }

std::string LiveRig::realtimeSummary() const {
  if (!run_ || clock_ != session::Clock::kRealTime) return "simulated clock";
  const servo::RealtimeReport& r = run_->loop().realtimeReport();
  if (r.fifo && r.memory_locked) return "SCHED_FIFO, memory locked";
  return r.fifo ? "SCHED_FIFO" : "normal scheduling";
}

}  // namespace hattr::studio
