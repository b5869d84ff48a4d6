#include "core/live_rig.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "hattr/core/error.hpp"
#include "hattr/device/device_uri.hpp"
#include "hattr/device/simulated_device.hpp"

namespace hattr::studio {
namespace {

constexpr std::size_t kRelayCapacity = 1024;                 // power of two
constexpr std::size_t kSimulatedChunk = 64;                  // ticks between drains, as runTrial
constexpr auto kRelayPoll = std::chrono::microseconds(500);  // as Recorder::startThread
constexpr double kLiftHeight_m = 0.003;                      // as runTrial's settle phase

std::string joined(const std::vector<std::string>& lines) {
  std::string out;
  for (const auto& line : lines) out += (out.empty() ? "" : "; ") + line;
  return out;
}

/// The device for a run, as runTrial opens it: a simulated pen starts just above where the
/// hand begins.
std::unique_ptr<device::Device> openRunDevice(const std::string& uri_text, device::HandScript& hand) {
  const device::DeviceUri uri = device::parseDeviceUri(uri_text);
  if (uri.scheme != "sim") return device::openDevice(uri_text, &hand);
  device::SimulatedPenParams params = device::simulatedPenParams(uri);
  hand.rewind();
  params.start_position_W = hand.command(0.0).p_target_W;
  params.start_position_W.z() = std::max(params.start_position_W.z(), kLiftHeight_m);
  hand.rewind();
  return std::make_unique<device::SimulatedDevice>(params, &hand, uri_text);
}

}  // namespace

/// The hand during the settle phase: the pen held lifted (above the script's first point as
/// runTrial does, or following a live hand); after it, the script.
class LiveRig::SettlingHand final : public device::HandScript {
 public:
  SettlingHand(device::HandScript& script, double settle_s, bool follow)
      : script_(script), settle_s_(settle_s), follow_(follow) {
    // Held above the first point at rest, exactly as runTrial's settle phase.
    script_.rewind();
    lifted_ = lift(script_.command(0.0));
    lifted_.v_target_W.setZero();
    script_.rewind();
  }
  device::HandCommand command(double t_s) noexcept override {
    if (follow_) return t_s < settle_s_ ? lift(script_.command(t_s)) : script_.command(t_s);
    return t_s < settle_s_ ? lifted_ : script_.command(t_s - settle_s_);
  }
  void rewind() noexcept override { script_.rewind(); }

 private:
  static device::HandCommand lift(device::HandCommand command) noexcept {
    command.pen_down = false;
    command.press_N = 0.0;
    command.v_target_W.z() = 0.0;
    if (command.p_target_W.z() < kLiftHeight_m) command.p_target_W.z() = kLiftHeight_m;
    return command;
  }

  device::HandScript& script_;
  double settle_s_;
  bool follow_;
  device::HandCommand lifted_;
};

RunSpec trialRunSpec(const session::TrialSetup& setup, bool follow_during_settle) {
  RunSpec spec;
  spec.guidance = setup.guidance;
  spec.reference = setup.reference;
  spec.metadata = setup.metadata;
  spec.record = setup.trigger == session::RecordTrigger::kPenDown ? RecordMode::kPenDown : RecordMode::kWindow;
  spec.settle_s = setup.settle_s;
  spec.duration_s = setup.duration_s;
  spec.follow_during_settle = follow_during_settle;
  return spec;
}

LiveRig::LiveRig() = default;

LiveRig::~LiveRig() { (void)finish(); }

void LiveRig::start(session::TrialEnvironment& environment, const RunSpec& spec, device::HandScript& hand,
                    session::Clock clock) {
  if (active()) (void)finish();
  HATTR_THROW_UNLESS(spec.record != RecordMode::kWindow ||
                         (std::isfinite(spec.duration_s) && spec.duration_s > 0.0 && spec.duration_s <= 3600.0),
                     "trial duration: expected (0, 3600] s, got {}", spec.duration_s);
  const double ramp_s = servo::SafetyConfig{}.ramp_time_s;
  HATTR_THROW_UNLESS(std::isfinite(spec.settle_s) && spec.settle_s >= ramp_s && spec.settle_s <= 60.0,
                     "settle time: expected [{}, 60] s (at least the safety ramp), got {}", ramp_s, spec.settle_s);
  HATTR_THROW_UNLESS(std::isfinite(spec.pen_up_stop_s) && spec.pen_up_stop_s > 0.0,
                     "pen-up stop time: expected > 0 s, got {}", spec.pen_up_stop_s);
  spec_ = spec;
  clock_ = clock;
  clamps_ = environment.worldClamps();

  // Guidance, its gains clamped to what the device renders passively with the paper
  // (both modes are clamped; the report names the one in use), as runTrial does.
  guidance::GuidanceConfig config = spec.guidance;
  const std::string_view active_mode = guidance::modeName(config.mode);
  for (auto& line :
       guidance::clampGains(config, environment.limits(), environment.rate_hz(), environment.impedance())) {
    if (config.mode != guidance::TrainingMode::kBasic && line.starts_with(active_mode))
      clamps_.push_back(std::move(line));
  }
  auto guidance = std::make_unique<guidance::TrainingGuidance>(spec.reference, config);
  guidance->startTrial(spec.settle_s);

  // Device, paper, loop; the hand settles before the script starts.
  auto settling = std::make_unique<SettlingHand>(hand, spec.settle_s, spec.follow_during_settle);
  auto device = openRunDevice(environment.deviceUri(), *settling);
  environment.paper().reset();
  auto loop = std::make_unique<servo::ServoLoop>(*device, servo::ServoConfig{.rate_hz = environment.rate_hz()});
  loop->setWorld(&environment.paper());
  loop->setGuidance(guidance.get());

  // The recording's metadata, as runTrial writes it.
  ProfileMetadata metadata = spec.metadata;
  metadata.device = environment.deviceUri();
  metadata.created_utc = utcNowIso8601();
  if (metadata.source.empty()) metadata.source = "recorded";
  auto& extra = metadata.extra;
  extra["mode"] = std::string(guidance::modeName(config.mode));
  extra["indexing"] = std::string(guidance::indexingName(config.playback.indexing));
  extra["speed"] = fmt::format("{}", config.playback.speed);
  extra["pcontrol_kp_N_per_m"] = fmt::format("{}", config.position.kp_N_per_m);
  extra["pcontrol_kd_N_s_per_m"] = fmt::format("{}", config.position.kd_N_s_per_m);
  extra["alpha_kp"] = fmt::format("{}", config.force.kp);
  extra["alpha_kd_s"] = fmt::format("{}", config.force.kd_s);
  extra["clamps"] = clamps_.empty() ? "none" : joined(clamps_);
  extra["clock"] = clock == session::Clock::kSimulated ? "simulated" : "real-time";

  // The recorder takes samples through a relay ring, so a trial's window starts and ends
  // at exact ticks whatever the clock.
  auto relay = std::make_unique<SpscRing<TickSample>>(kRelayCapacity);
  const session::RecorderConfig recorder_config{.trigger = spec.record == RecordMode::kPenDown
                                                               ? session::RecordTrigger::kPenDown
                                                               : session::RecordTrigger::kCommand,
                                                .nominal_period_s = 1.0 / environment.rate_hz(),
                                                .pen_up_stop_s = spec.pen_up_stop_s};
  auto recorder = std::make_unique<session::Recorder>(*relay, recorder_config, metadata);

  environment_ = &environment;
  settling_ = std::move(settling);
  device_ = std::move(device);
  guidance_ = std::move(guidance);
  loop_ = std::move(loop);
  relay_ = std::move(relay);
  recorder_ = std::move(recorder);
  const double half_period_s = 0.5 / environment.rate_hz();  // time stamps are not exact multiples
  window_begin_s_ = spec.settle_s - half_period_s;
  window_end_s_ = spec.settle_s + spec.duration_s - half_period_s;
  period_s_ = 1.0 / environment.rate_hz();
  window_armed_ = false;
  was_recording_ = false;
  status_recording_ = false;
  status_window_done_ = false;
  status_pen_down_done_ = false;
  status_recorded_ = 0;
  status_loop_time_s_ = 0.0;
  if (spec.record == RecordMode::kPenDown) recorder_->start();  // armed; records from the first pen-down

  if (clock == session::Clock::kRealTime) {
    loop_->requireConsumer(&recorder_->consumerTime());
    relay_stop_.store(false);
    relay_thread_ = std::thread([this] {
      while (!relay_stop_.load(std::memory_order_acquire)) {
        pump();
        std::this_thread::sleep_for(kRelayPoll);
      }
      pump();
    });
    try {
      loop_->start();
    } catch (...) {
      (void)finish();
      throw;
    }
  }
}

void LiveRig::advanceSimulated(double seconds) {
  HATTR_DEMAND(loop_ && clock_ == session::Clock::kSimulated, "advanceSimulated() needs a simulated run");
  const auto ticks = static_cast<std::size_t>(std::llround(seconds * environment_->rate_hz()));
  for (std::size_t done = 0; done < ticks; done += kSimulatedChunk) {
    loop_->runSimulated(std::min(kSimulatedChunk, ticks - done));
    pump();
  }
}

// Loop ring → relay → recorder. A trial's window arms and disarms the recorder at the
// exact sample, the recorder having taken everything before it.
void LiveRig::pump() {
  TickSample item;
  while (loop_->samples().tryPop(item)) {
    if (spec_.record == RecordMode::kWindow) {
      const bool in_window = item.sample.t_s >= window_begin_s_ && item.sample.t_s < window_end_s_;
      if (in_window != window_armed_) {
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
  recorder_->drain();
  publishStatus();
}

void LiveRig::publishStatus() {
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
  if (!loop_) return result;
  if (clock_ == session::Clock::kRealTime) {
    loop_->stop();
    relay_stop_.store(true, std::memory_order_release);
    if (relay_thread_.joinable()) relay_thread_.join();
  } else {
    pump();
  }
  recorder_->stop();

  result.clamps = clamps_;
  result.ticks = loop_->counters().ticks.load();
  result.overruns = loop_->counters().overruns.load();
  result.faults = loop_->counters().faults.load();
  result.missed_samples = recorder_->missed();
  result.profile = recorder_->takeProfile();

  // Tear down in dependency order: the recorder reads the relay, the loop drives the device.
  recorder_.reset();
  relay_.reset();
  loop_.reset();
  device_.reset();
  settling_.reset();
  guidance_.reset();
  environment_ = nullptr;
  return result;
}

void LiveRig::armRecording() noexcept {
  if (recorder_) recorder_->start();
}

void LiveRig::disarmRecording() noexcept {
  if (recorder_) recorder_->stop();
}

bool LiveRig::readLatest(Sample& out) noexcept { return loop_ ? loop_->latest().read(out) : false; }

bool LiveRig::post(const servo::ServoCommand& command) noexcept { return loop_ ? loop_->post(command) : false; }

bool LiveRig::switchMode(guidance::TrainingMode mode) noexcept {
  return post(servo::ServoCommand{.type = servo::ServoCommand::Type::kSetGuidanceParameter,
                                  .parameter = guidance::kParameterMode,
                                  .value = static_cast<double>(static_cast<int>(mode))});
}

RigStatus LiveRig::status() const noexcept {
  RigStatus status;
  if (!loop_) return status;
  status.running = clock_ == session::Clock::kSimulated || loop_->running();
  status.loop_time_s = status_loop_time_s_.load(std::memory_order_relaxed);
  status.settling = status.loop_time_s < spec_.settle_s;
  status.recording = status_recording_.load(std::memory_order_relaxed);
  status.window_done = status_window_done_.load(std::memory_order_acquire);
  status.pen_down_done = status_pen_down_done_.load(std::memory_order_acquire);
  status.recorded_samples = status_recorded_.load(std::memory_order_relaxed);
  return status;
}

const servo::LiveCounters* LiveRig::counters() const noexcept { return loop_ ? &loop_->counters() : nullptr; }

std::string LiveRig::realtimeSummary() const {
  if (!loop_ || clock_ != session::Clock::kRealTime) return "simulated clock";
  const servo::RealtimeReport& r = loop_->realtimeReport();
  if (r.fifo && r.memory_locked) return "SCHED_FIFO, memory locked";
  return r.fifo ? "SCHED_FIFO" : "normal scheduling";
}

}  // namespace hattr::studio
