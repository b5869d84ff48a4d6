#include "hattr/session/trial.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <thread>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "hattr/core/error.hpp"
#include "hattr/core/units.hpp"
#include "hattr/device/device_uri.hpp"
#include "hattr/guidance/strategy_catalog.hpp"
#include "hattr/guidance/strategy_schedule.hpp"
#include "hattr/servo/servo_loop.hpp"
#include "hattr/session/trial_run.hpp"
#include "hattr/session/trial_watch.hpp"

namespace hattr::session {
namespace {

/// The hand lifts the pen at least this high while settling.
constexpr double kLiftHeight_m = 0.003;

std::string joined(const std::vector<std::string>& lines) {
  std::string out;
  for (const auto& l : lines) out += (out.empty() ? "" : "; ") + l;
  return out;
}

/// The pen lifted: no press, at least the lift height, no vertical speed, no push.
device::HandCommand lifted(device::HandCommand command) noexcept {
  command.pen_down = false;
  command.press_N = 0.0;
  command.v_target_W.z() = 0.0;
  command.p_target_W.z() = std::max(command.p_target_W.z(), kLiftHeight_m);
  command.push_W.setZero();  // held still above the start: a force plan's push waits for the writing
  return command;
}

/// A real-time trial ends with its recording window (loop time); the wall clock ends it this
/// long after the window would have ended had the loop kept pace, whatever the loop's time says.
constexpr double kWindowEndBackstop_s = 2.0;

/// How a real-time wait ended: a failure (why), the end rule, a stop request, or the time ran out.
struct WaitEnd {
  std::string failure;
  bool writing_over = false;
  bool stopped = false;
};

/// Waits `seconds` of a real-time run, watching every 2 ms for what ends a trial early
/// (TrialWatch: a fault, a lost device, a stopped clock, a stuck loop); and, when given, the
/// recorder's end rule, the end of its window and a stop request. On a device whose clock is
/// simulated and pauses (Device::pausableClock), the seconds are the loop's, not the wall's.
WaitEnd waitForEnd(const servo::ServoLoop& loop, const device::Device& device, double seconds,
                   const Recorder* recorder = nullptr, const TrialStop* stop = nullptr) {
  using Clock = std::chrono::steady_clock;
  const auto until = Clock::now() + std::chrono::duration<double>(seconds);
  const auto until_tick = loop.counters().ticks.load() +
                          static_cast<std::uint64_t>(std::ceil(seconds / std::chrono::duration<double>(loop.period()).count()));
  const bool loop_time = device.pausableClock();
  TrialWatch watch(loop, device);
  while (loop_time ? loop.counters().ticks.load() < until_tick : Clock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    if (std::string failure = watch.check(); !failure.empty()) return {std::move(failure)};
    if (recorder != nullptr && recorder->writingOver()) return {.writing_over = true};
    if (recorder != nullptr && recorder->reachedEnd()) return {};
    if (stop != nullptr && stop->requested()) return {.stopped = true};
  }
  return {};
}

}  // namespace

SettlingHand::SettlingHand(device::HandScript& script, double settle_s, bool follow, const render::HeightField* relief)
    : script_(script), settle_s_(settle_s), follow_(follow), relief_(relief) {
  script_.rewind();
  lifted_ = lifted(script_.command(0.0));
  lifted_.v_target_W.setZero();
  script_.rewind();
}

device::HandCommand SettlingHand::command(double t_s) noexcept {
  device::HandCommand c = follow_ ? (t_s < settle_s_ ? lifted(script_.command(t_s)) : script_.command(t_s))
                                  : (t_s < settle_s_ ? lifted_ : script_.command(t_s - settle_s_));
  // Writing: the paper's surface under the target, where the fingers' reach is measured from.
  if (relief_ != nullptr && c.pen_down) c.surface_z_m = relief_->heightAt(c.p_target_W.x(), c.p_target_W.y());
  return c;
}

std::unique_ptr<device::Device> openTrialDevice(const std::string& uri_text, device::HandScript& hand) {
  const device::DeviceUri uri = device::parseDeviceUri(uri_text);
  if (uri.scheme != "sim" || uri.target != "pen") return device::openDevice(uri_text, &hand);
  device::SimulatedPenParams params = device::simulatedPenParams(uri);
  hand.rewind();
  params.start_position_W = hand.command(0.0).p_target_W;
  params.start_position_W.z() = std::max(params.start_position_W.z(), kLiftHeight_m);
  hand.rewind();
  return std::make_unique<device::SimulatedDevice>(params, &hand, uri_text);
}

std::vector<std::string> clampTrialGains(guidance::GuidanceConfig& config, const TrialEnvironment& env) {
  std::vector<std::string> clamps = env.worldClamps();
  // A scheduled strategy's clamps are its law's.
  const std::string_view active =
      guidance::modeName(guidance::isScheduled(config.mode) ? config.scheduled.law : config.mode);
  for (auto& line : guidance::clampGains(config, env.limits(), env.rate_hz(), env.impedance())) {
    if (config.mode != guidance::TrainingMode::kBasic && line.starts_with(active)) clamps.push_back(std::move(line));
  }
  return clamps;
}

ProfileMetadata trialMetadata(ProfileMetadata metadata, const TrialEnvironment& env, const guidance::GuidanceConfig& config,
                              const std::vector<std::string>& clamps, Clock clock) {
  metadata.device = env.deviceUri();
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
  // The strategies beyond the paper's: each of the active one's parameters, in its catalog unit
  // ("channel.half_width_mm"), after the clamps; NOISE's seed.
  if (static_cast<int>(config.mode) >= static_cast<int>(guidance::TrainingMode::kChannel)) {
    const std::string prefix = guidance::strategyName(config.mode);
    for (const auto& p : guidance::strategyInfo(config.mode).parameters) {
      extra[fmt::format("{}.{}", prefix, p.name)] = guidance::strategyParameterText(config, config.mode, p.name);
    }
    if (config.mode == guidance::TrainingMode::kNoise) extra["noise.seed"] = fmt::format("{}", config.noise.seed);
    // A scheduled strategy: the law and gain its schedule chose for this trial, and the law's
    // parameters beside its own ("pcontrol.kp_N_per_mm", ...).
    if (guidance::isScheduled(config.mode)) {
      const guidance::TrainingMode law = config.scheduled.law;
      extra["guidance_law"] = std::string(guidance::modeName(law));
      extra["guidance_gain"] = fmt::format("{}", config.scheduled.gain);
      for (const auto& p : guidance::strategyInfo(law).parameters) {
        extra[fmt::format("{}.{}", guidance::strategyName(law), p.name)] =
            guidance::strategyParameterText(config, law, p.name);
      }
    }
  }
  extra["clamps"] = clamps.empty() ? "none" : joined(clamps);
  extra["clock"] = clock == Clock::kSimulated ? "simulated" : "real-time";
  return metadata;
}

TrialEnvironment::TrialEnvironment(std::string device_uri, render::WorldConfig world, double rate_hz)
    : device_uri_(std::move(device_uri)), world_(std::move(world)), rate_hz_(rate_hz) {
  HATTR_THROW_UNLESS(std::isfinite(rate_hz) && rate_hz >= 1.0 && rate_hz <= 10'000.0,
                     "servo rate: expected 1 to 10000 Hz, got {}", rate_hz);
  relief_ = render::buildRelief(world_.relief);
  hand_relief_ = relief_.maxAbsHeight_m() > kHandFlatRelief_m;
  if (const auto declared = device::limitsWithoutOpening(device_uri_)) bindLimits(*declared);
}

namespace {

// What differs between a device's limits and the ones it had ("continuous force 1.4 N, now 0.9 N").
std::string limitsChange(const DeviceLimits& was, const DeviceLimits& now) {
  std::vector<std::string> parts;
  const auto number = [&](const char* what, double a, double b, const char* unit) {
    if (a != b) parts.push_back(fmt::format("{} {} {}, now {} {}", what, a, unit, b, unit));
  };
  const auto vector = [&](const char* what, const Vec3& a, const Vec3& b) {
    if (a != b) parts.push_back(fmt::format("{} ({}, {}, {}) m, now ({}, {}, {}) m", what, a.x(), a.y(), a.z(), b.x(), b.y(), b.z()));
  };
  if (was.degrees_of_freedom != now.degrees_of_freedom) {
    parts.push_back(fmt::format("{} degrees of freedom, now {}", was.degrees_of_freedom, now.degrees_of_freedom));
  }
  vector("workspace min", was.workspace_min_m, now.workspace_min_m);
  vector("workspace max", was.workspace_max_m, now.workspace_max_m);
  number("peak force", was.peak_force_N, now.peak_force_N, "N");
  number("continuous force", was.continuous_force_N, now.continuous_force_N, "N");
  number("max stiffness", was.max_stiffness_N_per_m, now.max_stiffness_N_per_m, "N/m");
  number("max damping", was.max_damping_N_s_per_m, now.max_damping_N_s_per_m, "N·s/m");
  number("nominal rate", was.nominal_rate_hz, now.nominal_rate_hz, "Hz");
  number("mass", was.mass_kg, now.mass_kg, "kg");
  number("damping", was.damping_N_s_per_m, now.damping_N_s_per_m, "N·s/m");
  return fmt::format("{}", fmt::join(parts, "; "));
}

}  // namespace

void TrialEnvironment::bindLimits(const DeviceLimits& limits) {
  if (limitsBound()) {
    HATTR_THROW_UNLESS(limits == limits_,
                       "device {}: its limits changed since the last trial ({}): a trial's environment is for one "
                       "device as it was; choose the device again (a new environment) to use it as it is now",
                       device_uri_, limitsChange(limits_, limits));
    return;
  }
  render::WorldConfig world = world_;
  std::vector<std::string> clamps = render::clampToDevice(world.paper, limits, rate_hz_);
  world.paper.normal_from_pressure = limits.degrees_of_freedom == 2;  // a planar pen on its table
  paper_ = std::make_unique<render::PaperRenderer>(world.paper, relief_);
  world_ = std::move(world);
  world_clamps_ = std::move(clamps);
  limits_ = limits;
}

const DeviceLimits& TrialEnvironment::limits() const {
  HATTR_DEMAND(limitsBound(), "device {}: its limits are read before a trial opened it", device_uri_);
  return limits_;
}

render::PaperRenderer& TrialEnvironment::paper() {
  HATTR_DEMAND(limitsBound(), "device {}: the paper is used before a trial opened the device", device_uri_);
  return *paper_;
}

const std::vector<std::string>& TrialEnvironment::worldClamps() const {
  HATTR_DEMAND(limitsBound(), "device {}: the world's clamps are read before a trial opened the device", device_uri_);
  return world_clamps_;
}

guidance::WorldImpedance TrialEnvironment::impedance() const noexcept {
  return {.normal_stiffness_N_per_m = world_.paper.contact.stiffness_N_per_m,
          .normal_damping_N_s_per_m = world_.paper.contact.damping_N_s_per_m,
          .tangential_stiffness_N_per_m = world_.paper.tangential_stiffness_N_per_m};
}

std::string disturbanceOf(const TrialResult& r) {
  std::vector<std::string> parts;
  const auto add = [&parts](std::uint64_t n, const char* one, const char* many) {
    if (n > 0) parts.push_back(fmt::format("{} {}", n, n == 1 ? one : many));
  };
  add(r.stalls, "stall (force zeroed)", "stalls (force zeroed)");
  add(r.missed_samples, "missed sample", "missed samples");
  add(r.faults, "safety fault", "safety faults");
  add(r.link_faults, "lost device link", "lost device links");
  add(r.mentor_link_faults, "lost link to the mentor", "lost links to the mentor");
  const std::string physical = describePhysicalEvents(r.physics);
  if (!physical.empty()) parts.push_back(physical);
  return fmt::format("{}", fmt::join(parts, " · "));
}

std::string noteLoopCounters(TrialResult& result) {
  notePhysicalEvents(result.physics, result.profile.metadata());
  const std::string disturbed = disturbanceOf(result);
  auto& extra = result.profile.metadata().extra;
  extra["loop_ticks"] = fmt::format("{}", result.ticks);
  extra["loop_overruns"] = fmt::format("{}", result.overruns);
  extra["loop_stalls"] = fmt::format("{}", result.stalls);
  extra["missed_samples"] = fmt::format("{}", result.missed_samples);
  extra["safety_faults"] = fmt::format("{}", result.faults);
  extra["device_link_faults"] = fmt::format("{}", result.link_faults);
  if (result.mentor_link_faults > 0) extra["mentor_link_faults"] = fmt::format("{}", result.mentor_link_faults);
  if (!disturbed.empty()) extra["disturbed"] = disturbed;
  return disturbed;
}

void noteTrialEnd(TrialResult& result, Recorder& recorder, bool stopped) {
  result.end_reason = std::string(!result.failure.empty() ? kEndFailed
                                  : recorder.writingOver() ? kEndPenLifted
                                  : stopped               ? kEndStopped
                                                          : kEndMaximumDuration);
  result.writing_begin_s = recorder.writingBegin_s();
  result.writing_end_s = recorder.writingEnd_s();
  result.profile = recorder.takeProfile();
  auto& extra = result.profile.metadata().extra;
  extra["end_reason"] = result.end_reason;
  if (result.writing_begin_s >= 0.0) {
    extra["writing_begin_s"] = fmt::format("{}", result.writing_begin_s);
    extra["writing_end_s"] = fmt::format("{}", result.writing_end_s);
  }
}

Clock parseClock(std::string_view name) {
  if (name == "sim") return Clock::kSimulated;
  if (name == "real") return Clock::kRealTime;
  throw InputError(fmt::format("clock \"{}\": expected sim or real", name));
}

namespace {

// The strategy a "STRATEGY.KEY" setting names; InputError naming the setting otherwise.
guidance::TrainingMode strategyOfSetting(const guidance::StrategySetting& setting, std::string_view strategy) {
  try {
    return guidance::parseMode(strategy);
  } catch (const InputError& e) {
    throw InputError(fmt::format("parameter \"{}={}\": the strategy before the dot: {}", setting.first,
                                 setting.second, e.what()));
  }
}

// KEY=VALUE (or MODE.KEY=VALUE): the strategy's own parameter; STRATEGY.KEY=VALUE, for a scheduled
// strategy, a law's it may play, as a study file's strategy_parameters sets it (pcontrol.kp_N_per_mm).
void setTrialParameters(guidance::GuidanceConfig& config, guidance::TrainingMode mode,
                        const std::vector<guidance::StrategySetting>& settings) {
  std::vector<guidance::StrategySetting> own;
  std::map<guidance::TrainingMode, std::vector<guidance::StrategySetting>> others;
  for (const auto& setting : settings) {
    const auto& [key, value] = setting;
    const auto dot = key.find('.');
    const guidance::TrainingMode named = dot == std::string::npos ? mode : strategyOfSetting(setting, key.substr(0, dot));
    const std::string name = dot == std::string::npos ? key : key.substr(dot + 1);
    if (named == mode) {
      own.emplace_back(name, value);
      continue;
    }
    HATTR_THROW_UNLESS(guidance::isScheduled(mode) && !guidance::isScheduled(named) && !guidance::isMentored(named),
                       "parameter \"{}={}\": {} plays no other strategy's law; expected its own parameters "
                       "(KEY=VALUE, `hattr strategies`), got {}'s",
                       key, value, guidance::strategyName(mode), guidance::strategyName(named));
    others[named].emplace_back(name, value);
  }
  guidance::setStrategyParameters(config, mode, own);
  for (const auto& [other, its] : others) guidance::setStrategyParameters(config, other, its);
}

}  // namespace

TrialSetup scriptedTrialSetup(const device::ProfileHandScript& hand, const HapticProfile& script,
                              const ScriptedTrialOptions& options) {
  HATTR_THROW_UNLESS(!guidance::isMentored(options.mode),
                     "mode {}: a mentored strategy's guidance comes from a live expert's station: run it with "
                     "`hattr mentor` (docs/mentoring.md)", guidance::strategyName(options.mode));
  HATTR_THROW_UNLESS(options.expert != nullptr || !guidance::needsReference(options.mode),
                     "a trial in mode {} needs a reference (the expert's profile); only BASIC runs without one",
                     guidance::modeName(options.mode));
  TrialSetup setup;
  // The end: the script's length plus the tail, or the end rule with its longest trial.
  setup.duration_s = hand.duration_s() + options.tail_s;
  if (options.pen_up_end_s > 0.0) {
    setup.pen_up_end_s = options.pen_up_end_s;
    setup.duration_s = options.max_duration_s > 0.0 ? options.max_duration_s
                                                     : std::min(3.0 * hand.duration_s(), 3600.0);
  }
  setup.clock = options.clock;
  // What the recording says about itself.
  const bool training = options.expert != nullptr;
  setup.metadata.subject = !options.subject.empty() ? options.subject : training ? "trainee" : "expert";
  setup.metadata.skill = options.skill.empty() ? script.metadata().skill : options.skill;
  setup.metadata.extra["hand_script"] = options.hand_label;
  if (!training) return setup;
  // Training: the expert resampled at the servo rate, and the mode's guidance.
  setup.reference = std::make_shared<guidance::ReferenceTrajectory>(*options.expert, options.rate_hz);
  setup.guidance.mode = options.mode;
  setup.guidance.playback.indexing = options.indexing;
  setup.guidance.playback.speed = options.speed;
  setTrialParameters(setup.guidance, options.mode, options.parameters);
  setup.guidance.scheduled = guidance::scheduleTrial(setup.guidance, options.mode, {});  // a first trial
  setup.guidance.noise.seed = options.seed;
  setup.metadata.extra["reference"] = options.reference_label;
  setup.metadata.extra["trial"] = fmt::format("{}", options.trial);
  if (setup.metadata.skill.empty()) setup.metadata.skill = options.expert->metadata().skill;
  return setup;
}

TrialResult runTrial(TrialEnvironment& env, const TrialSetup& setup, device::HandScript& hand) {
  TrialRun run(env, setup, hand);
  servo::ServoLoop& loop = run.loop();
  const double settle_s = run.settle_s();
  // In real time the recording is the loop-time window [settle, settle + duration): its
  // length does not depend on when this thread wakes to start and stop it.
  RecorderConfig recorder_config = run.recorderConfig();
  if (run.clock() == Clock::kRealTime) {
    recorder_config.window_begin_s = settle_s;
    recorder_config.window_end_s = settle_s + setup.duration_s;
  }
  Recorder recorder(loop.samples(), recorder_config, run.metadata());

  const auto settle_ticks = static_cast<std::size_t>(std::llround(settle_s * env.rate_hz()));
  auto ticks = static_cast<std::size_t>(std::llround(setup.duration_s * env.rate_hz()));
  // The end: the recorder decides the end rule sample by sample (it stops recording with the
  // sample that ends the trial); between chunks, or every 2 ms in real time, we stop the loop.
  std::string failure;
  bool stopped = false;
  if (run.clock() == Clock::kSimulated) {
    const auto advance = [&](std::size_t count) {
      for (std::size_t done = 0; done < count && !recorder.writingOver(); done += kSimulatedChunk) {
        loop.runSimulated(std::min(kSimulatedChunk, count - done));
        recorder.drain();
      }
    };
    advance(settle_ticks);
    failure = run.mentorUnavailable();
    if (!failure.empty()) ticks = 0;  // no mentor: nothing is recorded
    recorder.start();
    // A host stall injected at its time (rehearsing a study's policy), else straight through.
    const auto stall_tick = setup.inject_stall_at_s >= 0.0
                                ? std::min(ticks, static_cast<std::size_t>(std::llround(setup.inject_stall_at_s * env.rate_hz())))
                                : ticks;
    advance(stall_tick);
    if (stall_tick < ticks) {
      loop.delaySimulated(std::chrono::nanoseconds(units::secondsToNanoseconds(setup.injected_stall_s)));
      advance(ticks - stall_tick);
    }
  } else {
    loop.requireConsumer(&recorder.consumerTime());
    recorder.startThread();
    recorder.start();  // armed from the first tick: the window decides what is kept
    loop.start();
    failure = waitForEnd(loop, run.device(), settle_s).failure;
    if (failure.empty()) failure = run.mentorUnavailable();
    if (failure.empty()) {
      // Until the window's end; the wall clock only backs it up for a loop far behind it.
      const WaitEnd end = waitForEnd(loop, run.device(), setup.duration_s + kWindowEndBackstop_s, &recorder, setup.stop);
      failure = end.failure;
      stopped = end.stopped;
    }
    // Nothing after the end (a fault, a stop request) is recorded, and nothing before it lost
    // however far the recorder's thread is behind the loop.
    recorder.stopBefore(loop.counters().ticks.load());
    loop.stop();
    recorder.stopThread();
  }
  recorder.stop();

  TrialResult result = run.finish(recorder, std::move(failure), stopped);
  if (result.profile.empty() && result.failure.empty()) {
    throw Error("the trial recorded no samples (with the pen-down trigger: the pen never touched the paper)");
  }
  return result;
}

TrialErrors trialErrors(const HapticProfile& trial, const guidance::ReferenceTrajectory& reference) {
  TrialErrors errors;
  std::size_t n = 0;
  for (const Sample& s : trial.samples()) {
    const double index = s.t_s / reference.dt_s();
    if (index > static_cast<double>(reference.size() - 1)) break;
    const guidance::ReferencePoint r = reference.at(index);
    errors.position_rms_m += (s.p_WT - r.p_WT).head<2>().squaredNorm();
    errors.force_rms_N += (s.f_user_W - r.f_W).squaredNorm();
    ++n;
  }
  if (n > 0) {
    errors.position_rms_m = std::sqrt(errors.position_rms_m / static_cast<double>(n));
    errors.force_rms_N = std::sqrt(errors.force_rms_N / static_cast<double>(n));
  }
  return errors;
}

}  // namespace hattr::session
