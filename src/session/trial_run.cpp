#include "hattr/session/trial_run.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include <fmt/format.h>

#include "hattr/core/error.hpp"

namespace hattr::session {
namespace {

/// The set-up's numbers a trial can run with; InputError otherwise.
void checkSetup(const TrialSetup& setup) {
  HATTR_THROW_UNLESS(std::isfinite(setup.duration_s) && setup.duration_s > 0.0 && setup.duration_s <= 3600.0,
                     "trial duration: expected (0, 3600] s, got {}", setup.duration_s);
  HATTR_THROW_UNLESS(std::isfinite(setup.pen_up_end_s) && setup.pen_up_end_s >= 0.0 && setup.pen_up_end_s <= 60.0,
                     "trial end: pen-up time: expected [0, 60] s (0: off), got {}", setup.pen_up_end_s);
  const double ramp_s = servo::SafetyConfig{}.ramp_time_s;
  HATTR_THROW_UNLESS(std::isfinite(setup.settle_s) && setup.settle_s >= ramp_s && setup.settle_s <= 60.0,
                     "trial settle time: expected [{}, 60] s (at least the safety ramp), got {}", ramp_s, setup.settle_s);
  HATTR_THROW_UNLESS(setup.live_guidance != nullptr || !guidance::isMentored(setup.guidance.mode),
                     "mode {}: a mentored mode needs an expert's station (a study file's mentor block, or "
                     "`hattr mentor follow` for a session outside a study)", guidance::modeName(setup.guidance.mode));
}

}  // namespace

TrialRun::TrialRun(TrialEnvironment& environment, const TrialSetup& setup, device::HandScript& hand,
                   bool follow_during_settle)
    : environment_(&environment), bounds_(environment.physicalBounds()) {
  checkSetup(setup);
  // The hand settles before the script starts (a mentored mode's settle long enough for the link).
  live_ = guidance::isMentored(setup.guidance.mode) ? setup.live_guidance : nullptr;
  settle_s_ = live_ ? std::max(setup.settle_s, live_->minimumSettle_s()) : setup.settle_s;
  settling_ = std::make_unique<SettlingHand>(hand, settle_s_, follow_during_settle, environment.handRelief());
  // The device is opened once for the trial, as late as it can be: right before the loop when its
  // limits are known (a simulated pen's, or a later trial's of the same environment), else first,
  // for the guidance's gains are clamped to them (a served pen then waits while the guidance is
  // built: milliseconds, longer for a simulated mentor's station).
  const bool open_first = !environment.limitsBound();
  if (open_first) openDevice(environment, setup);

  // Guidance, with its gains clamped to what the device renders passively with the paper; a
  // mentored mode's comes live from the expert's pen.
  guidance::GuidanceConfig config = setup.guidance;
  clamps_ = clampTrialGains(config, environment);
  guidance_ = std::make_unique<guidance::TrainingGuidance>(setup.reference, config);
  GuidanceController& stage = live_ ? live_->beginTrial(config.mode, environment, settle_s_, setup.live_seed)
                                    : static_cast<GuidanceController&>(*guidance_);
  guidance_->startTrial(settle_s_);
  if (!open_first) openDevice(environment, setup);

  // Paper and loop. A device that cannot be simulated runs in real time whatever the setup asks.
  clock_ = device_->clocking() == device::DeviceClocking::kSimulatable ? setup.clock : Clock::kRealTime;
  environment.paper().reset();
  // In simulated time the ring is drained every kSimulatedChunk ticks, so a small ring does (a
  // real-time loop keeps the default, seconds of samples, for a late consumer).
  servo::ServoConfig servo_config{.rate_hz = environment.rate_hz()};
  if (clock_ == Clock::kSimulated) servo_config.sample_ring_capacity = 16 * kSimulatedChunk;
  loop_ = std::make_unique<servo::ServoLoop>(*device_, servo_config);
  loop_->setWorld(&environment.paper());
  loop_->setGuidance(&stage);

  // What the recording says about itself, and the recorder's end rule.
  metadata_ = trialMetadata(setup.metadata, environment, config, clamps_, clock_);
  if (clock_ == Clock::kRealTime && device_->clocking() == device::DeviceClocking::kDeviceClock) {
    metadata_.extra["clock"] = "device";
  }
  recorder_config_ = {.trigger = setup.trigger, .nominal_period_s = 1.0 / environment.rate_hz()};
  recorder_config_.end_after_pen_up_s = setup.pen_up_end_s;
  if (setup.pen_up_end_s > 0.0) recorder_config_.pen_up_stop_s = setup.pen_up_end_s;
}

TrialRun::~TrialRun() = default;

void TrialRun::openDevice(TrialEnvironment& environment, const TrialSetup& setup) {
  device_ = openTrialDevice(environment.deviceUri(), *settling_);
  environment.bindLimits(device_->limits());
  if (setup.check_device) setup.check_device(environment.limits());
}

std::string TrialRun::mentorUnavailable() const { return live_ ? live_->unavailable() : std::string(); }

TrialResult TrialRun::finish(Recorder& recorder, std::string failure, bool stopped) {
  TrialResult result;
  result.clamps = clamps_;
  result.failure = std::move(failure);
  const auto& counters = loop_->counters();
  result.ticks = counters.ticks.load();
  result.overruns = counters.overruns.load();
  result.faults = counters.faults.load();
  result.link_faults = counters.link_faults.load();
  result.stalls = counters.stalls.load();
  result.max_period_error_s = static_cast<double>(loop_->periodError().max_ns()) * 1e-9;
  result.clock = std::string(servo::loopClockName(loop_->clock()));
  result.missed_samples = recorder.missed();
  // The mentor's session ends with the loop; its notes go with the recording.
  const std::map<std::string, std::string> live_notes = live_ ? live_->endTrial(result) : std::map<std::string, std::string>{};
  noteTrialEnd(result, recorder, stopped);
  auto& extra = result.profile.metadata().extra;
  extra.insert(live_notes.begin(), live_notes.end());
  if (!result.failure.empty()) extra["failed"] = result.failure;
  if (result.link_faults > 0) {
    extra["link_faults"] = fmt::format("{} ({} ticks without the device, force zeroed)", result.link_faults,
                                       counters.disconnected_ticks.load());
  }
  // What the recording did that a good trial does not, and every counter, in its metadata.
  result.physics = judgeRecording(result.profile, environment_->limits(), loop_->safety().maxForce_N(),
                                  environment_->paper().relief(), bounds_);
  noteLoopCounters(result);
  return result;
}

}  // namespace hattr::session
