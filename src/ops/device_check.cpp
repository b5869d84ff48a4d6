#include "hattr/ops/device_check.hpp"

#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/device/device_uri.hpp"
#include "hattr/device/hand.hpp"
#include "hattr/ops/json.hpp"

namespace hattr::ops {
namespace {

using Clock = std::chrono::steady_clock;

/// A constant force along `direction` while switched on through the loop's mailbox (parameter 0 [N]).
class TestForce final : public GuidanceController {
 public:
  explicit TestForce(const Vec3& direction) : direction_(direction) {}
  Vec3 compute(const PenState&, const ContactForces&, double) noexcept override { return force_N_ * direction_; }
  bool setParameter(int parameter, double value) noexcept override {
    if (parameter != 0) return false;
    force_N_ = value;
    return true;
  }

 private:
  Vec3 direction_;
  double force_N_ = 0.0;
};

/// The test force's direction: up, or on a planar pen (which cannot push up) away from the writer.
Vec3 testDirection(const DeviceLimits& limits) { return limits.degrees_of_freedom == 2 ? Vec3::UnitY() : Vec3::UnitZ(); }

nlohmann::json limitsJson(const DeviceLimits& l) {
  return {{"peak_force_N", l.peak_force_N},
          {"continuous_force_N", l.continuous_force_N},
          {"max_stiffness_N_per_m", l.max_stiffness_N_per_m},
          {"max_damping_N_s_per_m", l.max_damping_N_s_per_m},
          {"nominal_rate_hz", l.nominal_rate_hz},
          {"workspace_min_m", {l.workspace_min_m.x(), l.workspace_min_m.y(), l.workspace_min_m.z()}},
          {"workspace_max_m", {l.workspace_max_m.x(), l.workspace_max_m.y(), l.workspace_max_m.z()}}};
}

// The gentle force: ramped in by the safety path, held 1 s (up to 5 s while stalls of the host
// keep restarting the ramp, until a latched fault), then off. Fills the force test's figures.
// Posts until the mailbox takes the command (it turns one away only while full, or while another
// thread posts), for a second at most: a loop that stopped draining it is past helping.
void postUntilTaken(servo::ServoLoop& loop, const servo::ServoCommand& command) {
  const auto give_up = Clock::now() + std::chrono::seconds(1);
  while (!loop.post(command) && Clock::now() < give_up) std::this_thread::sleep_for(std::chrono::milliseconds(1));
}

void applyTestForce(servo::ServoLoop& loop, double force_N, const Vec3& direction, DeviceCheckResult& r) {
  Sample before;
  (void)loop.latest().read(before);
  postUntilTaken(loop, {servo::ServoCommand::Type::kSetGuidanceParameter, 0, force_N});
  Sample during;
  const auto reached = [&] { return std::abs(during.f_cmd_W.dot(direction) - force_N) < 0.02 * force_N; };
  const auto faulted = [&] { return loop.counters().faults.load() > 0; };
  const auto held_from = Clock::now();
  while ((Clock::now() - held_from < std::chrono::seconds(1) ||
          (!reached() && Clock::now() - held_from < std::chrono::seconds(5))) &&
         !faulted()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    Sample now;
    if (loop.latest().read(now) && now.f_cmd_W.dot(direction) >= during.f_cmd_W.dot(direction)) during = now;
  }
  postUntilTaken(loop, {servo::ServoCommand::Type::kSetGuidanceParameter, 0, 0.0});
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  r.commanded_N = during.f_cmd_W.dot(direction);
  r.pen_rise_m = (during.p_WT - before.p_WT).dot(direction);
  r.force_reached = reached();
}

}  // namespace

std::string_view clockingName(device::DeviceClocking clocking) noexcept {
  switch (clocking) {
    case device::DeviceClocking::kSimulatable: return "host (simulatable)";
    case device::DeviceClocking::kHostRealTime: return "host";
    case device::DeviceClocking::kDeviceClock: return "device";
  }
  return "unknown";
}

bool DeviceCheckResult::ok() const noexcept {
  return judgement.overall != servo::Verdict::kFail && force_reached && confirmed.value_or(true);
}

nlohmann::json DeviceCheckResult::toJson() const {
  const DeviceCapabilities& c = device.capabilities;
  return {
      {"device", device.uri},
      {"clocking", std::string(clockingName(device.clocking))},
      {"loop_clock", std::string(servo::loopClockName(loop_clock))},
      {"rate_hz", device.rate_hz},
      {"limits", limitsJson(device.limits)},
      {"capabilities", {{"force_sensor", c.force_sensor}, {"pressure", c.pressure}, {"tilt", c.tilt}}},
      {"period_error_us", percentilesUsJson(period_error)},
      {"ticks", figures.ticks},
      {"overruns", figures.overruns},
      {"faults", figures.faults},
      {"link_faults", figures.link_faults},
      {"stalls", figures.stalls},
      {"fault_reason", fault_reason},
      {"force_test",
       {{"direction", force_direction},
        {"commanded_N", commanded_N},
        {"pen_rise_m", pen_rise_m},
        {"confirmed", confirmed ? nlohmann::json(*confirmed) : nlohmann::json(nullptr)}}},
      {"verdicts", verdictsJson(judgement)},
      {"verdict", std::string(servo::verdictName(judgement.overall))},
      {"ok", ok()},
  };
}

// Open → describe → the loop with nothing rendered (jitter) → the gentle force → the answer →
// the verdicts.
DeviceCheckResult runDeviceCheck(const DeviceCheckOptions& options) {
  HATTR_THROW_UNLESS(std::isfinite(options.seconds) && options.seconds >= 0.1 && options.seconds <= 60.0,
                     "device check: seconds: expected 0.1 to 60 s, got {}", options.seconds);
  // A simulated pen is held lightly by a simulated hand, 10 mm above the paper, as a person
  // would hold a real one (real devices ignore it).
  device::StillHand hand(device::HandCommand{.p_target_W = Vec3(0.0, 0.0, 0.01)});
  const auto device = device::openDevice(options.uri, &hand);
  DeviceCheckResult r;
  r.device = {.uri = options.uri,
              .clocking = device->clocking(),
              .rate_hz = options.rate_hz > 0.0 ? options.rate_hz : device->limits().nominal_rate_hz,
              .limits = device->limits(),
              .capabilities = device->capabilities()};
  HATTR_THROW_UNLESS(options.force_N > 0.0 && options.force_N <= r.device.limits.continuous_force_N,
                     "--force-N: expected (0, {}] N (the device's continuous force), got {}",
                     r.device.limits.continuous_force_N, options.force_N);
  if (options.opened) options.opened(r.device);

  const Vec3 direction = testDirection(r.device.limits);
  r.force_direction = direction.z() > 0.0 ? "up" : "away from the writer";
  TestForce force(direction);
  servo::ServoLoop loop(*device, servo::ServoConfig{.rate_hz = r.device.rate_hz});
  loop.setGuidance(&force);
  loop.start();
  std::atomic<bool> draining{true};
  std::jthread drain([&] {
    TickSample s;
    while (draining.load()) {
      while (loop.samples().tryPop(s)) {
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  });
  std::this_thread::sleep_for(std::chrono::duration<double>(options.seconds));
  if (options.announce && options.confirm) {
    options.announce(fmt::format("Hold the pen lightly: a {} N {} follows for about 1 s.", options.force_N,
                                 direction.z() > 0.0 ? "upward force" : "force away from you"));
  }
  r.force_N = options.force_N;
  applyTestForce(loop, options.force_N, direction, r);
  loop.stop();
  draining = false;
  drain.join();
  if (options.confirm) r.confirmed = options.confirm();

  // The device must run clean; what the computer's scheduling does is a WARN (docs/realtime.md).
  r.loop_clock = loop.clock();
  r.period_error = loop.periodError();
  r.figures = servo::figuresOf(loop);
  r.fault_reason = device->faultReason();
  r.judgement = servo::judgeLoop(r.figures);
  return r;
}

}  // namespace hattr::ops
