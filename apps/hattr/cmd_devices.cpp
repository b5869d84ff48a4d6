// hattr devices (alias: device): the device kinds and URIs hattr accepts, the plugins it finds,
// and `devices check URI`, which a lab runs on a new device: limits, rate, a jitter
// measurement and a gentle force the person confirms. `device serve` and `device keygen` are
// in cmd_device_serve.cpp.

#include <cmath>
#include <iostream>
#include <thread>

#include <fmt/format.h>
#include <unistd.h>

#include "cli_common.hpp"
#include "hattr/core/error.hpp"
#include "hattr/device/device_uri.hpp"
#include "hattr/device/hand.hpp"
#include "hattr/device/plugin_device.hpp"
#include "hattr/servo/servo_loop.hpp"

namespace hattr::cli {
namespace {

struct CheckOptions {
  std::string uri;
  double seconds = 2.0;
  double force_N = 0.2;
  double rate_hz = 0.0;
  bool no_confirm = false;
  bool json = false;
};

/// A constant upward force while switched on through the loop's mailbox (parameter 0 [N]).
class TestForce final : public GuidanceController {
 public:
  Vec3 compute(const PenState&, const ContactForces&, double) noexcept override { return Vec3(0.0, 0.0, force_N_); }
  bool setParameter(int parameter, double value) noexcept override {
    if (parameter != 0) return false;
    force_N_ = value;
    return true;
  }

 private:
  double force_N_ = 0.0;
};

std::string kindsText() {
  std::string text = device::deviceUriHelp();
  const auto plugins = device::findPlugins();
  text += "\nplugins found (plugin:NAME, or plugin:/path/libX.so):\n";
  if (plugins.empty()) text += "  none (search path: $HATTR_PLUGIN_PATH, then beside the hattr program)\n";
  for (const auto& p : plugins) text += fmt::format("  {:<14} {}\n    {}\n", p.name, p.description, p.path);
  text += "\nCheck a device before a study: hattr devices check URI (docs/devices.md).\n";
  return text;
}

nlohmann::json limitsJson(const DeviceLimits& l) {
  return {{"peak_force_N", l.peak_force_N},
          {"continuous_force_N", l.continuous_force_N},
          {"max_stiffness_N_per_m", l.max_stiffness_N_per_m},
          {"max_damping_N_s_per_m", l.max_damping_N_s_per_m},
          {"nominal_rate_hz", l.nominal_rate_hz},
          {"workspace_min_m", {l.workspace_min_m.x(), l.workspace_min_m.y(), l.workspace_min_m.z()}},
          {"workspace_max_m", {l.workspace_max_m.x(), l.workspace_max_m.y(), l.workspace_max_m.z()}}};
}

std::string_view clockingName(device::DeviceClocking c) {
  switch (c) {
    case device::DeviceClocking::kSimulatable: return "host (simulatable)";
    case device::DeviceClocking::kHostRealTime: return "host";
    case device::DeviceClocking::kDeviceClock: return "device";
  }
  return "unknown";
}

/// Asks the person a yes/no question on the terminal; nullopt when nobody answers (no input).
std::optional<bool> askPerson(const std::string& question) {
  std::cerr << question << " [y/n] " << std::flush;
  std::string answer;
  if (!std::getline(std::cin, answer)) return std::nullopt;
  return !answer.empty() && (answer[0] == 'y' || answer[0] == 'Y');
}

// Open → describe → run the loop for the jitter measurement → the gentle force → verdict.
int runCheck(const CheckOptions& opt) {
  // A simulated pen is held lightly by a simulated hand, 10 mm above the paper, as a person
  // would hold a real one (real devices ignore it).
  device::StillHand hand(device::HandCommand{.p_target_W = Vec3(0.0, 0.0, 0.01)});
  const auto device = device::openDevice(opt.uri, &hand);
  const DeviceLimits& limits = device->limits();
  HATTR_THROW_UNLESS(opt.force_N > 0.0 && opt.force_N <= limits.continuous_force_N,
                     "--force-N: expected (0, {}] N (the device's continuous force), got {}", limits.continuous_force_N,
                     opt.force_N);
  const double rate_hz = opt.rate_hz > 0.0 ? opt.rate_hz : limits.nominal_rate_hz;
  if (!opt.json) {
    std::cout << fmt::format("device      {}\nclock       {}\nrate        {} Hz\nforce       {} N continuous, {} N peak\n"
                             "stiffness   {} N/m max\n",
                             opt.uri, clockingName(device->clocking()), rate_hz, limits.continuous_force_N,
                             limits.peak_force_N, limits.max_stiffness_N_per_m)
              << std::flush;
  }

  // The loop with nothing but the test force (off while measuring jitter).
  TestForce force;
  servo::ServoLoop loop(*device, servo::ServoConfig{.rate_hz = rate_hz});
  loop.setGuidance(&force);
  loop.start();
  std::atomic<bool> draining{true};
  std::thread drain([&] {
    TickSample s;
    while (draining.load()) {
      while (loop.samples().tryPop(s)) {
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  });
  const auto stop_all = [&] {
    loop.stop();
    draining = false;
    drain.join();
  };
  std::this_thread::sleep_for(std::chrono::duration<double>(opt.seconds));
  Sample before;
  (void)loop.latest().read(before);
  const double z_before_m = before.p_WT.z();

  // The gentle force: announced, ramped in by the safety path, held 1 s, then off.
  std::optional<bool> confirmed;
  if (!opt.no_confirm) std::cerr << fmt::format("Hold the pen lightly: a {} N upward force follows for about 1 s.\n", opt.force_N);
  (void)loop.post({servo::ServoCommand::Type::kSetGuidanceParameter, 0, opt.force_N});
  // The force reached while held: the largest commanded, and the pen's rise at that moment.
  // Held 1 s; longer (up to 5 s) while stalls of the host keep restarting the ramp.
  Sample during;
  const auto reached = [&] { return std::abs(during.f_cmd_W.z() - opt.force_N) < 0.02 * opt.force_N; };
  const auto held_from = std::chrono::steady_clock::now();
  // A latched fault ends the wait: no force follows it.
  const auto faulted = [&] { return loop.counters().faults.load() > 0; };
  while ((std::chrono::steady_clock::now() - held_from < std::chrono::seconds(1) ||
          (!reached() && std::chrono::steady_clock::now() - held_from < std::chrono::seconds(5))) &&
         !faulted()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    Sample now;
    if (loop.latest().read(now) && now.f_cmd_W.z() >= during.f_cmd_W.z()) during = now;
  }
  (void)loop.post({servo::ServoCommand::Type::kSetGuidanceParameter, 0, 0.0});
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  stop_all();
  if (!opt.no_confirm) confirmed = askPerson("Did you feel a gentle upward push?");

  const auto& c = loop.counters();
  const auto& pe = loop.periodError();
  // The device must run clean; what the computer's scheduling does is a WARN (docs/realtime.md).
  const servo::LoopJudgement judgement = servo::judgeLoop(loop);
  const bool force_ok = reached();
  const bool ok = judgement.overall != servo::Verdict::kFail && force_ok && confirmed.value_or(true);
  const auto us = [](std::int64_t ns) { return static_cast<double>(ns) * 1e-3; };
  nlohmann::json json = {
      {"device", opt.uri},
      {"clocking", std::string(clockingName(device->clocking()))},
      {"loop_clock", std::string(servo::loopClockName(loop.clock()))},
      {"rate_hz", rate_hz},
      {"limits", limitsJson(limits)},
      {"capabilities", {{"force_sensor", device->capabilities().force_sensor}, {"pressure", device->capabilities().pressure},
                        {"tilt", device->capabilities().tilt}}},
      {"period_error_us", {{"p50", us(pe.percentile_ns(0.5))}, {"p99", us(pe.percentile_ns(0.99))},
                           {"p99_9", us(pe.percentile_ns(0.999))}, {"max", us(pe.max_ns())}, {"count", pe.count()}}},
      {"ticks", c.ticks.load()},
      {"overruns", c.overruns.load()},
      {"faults", c.faults.load()},
      {"link_faults", c.link_faults.load()},
      {"stalls", c.stalls.load()},
      {"fault_reason", device->faultReason()},
      {"force_test", {{"commanded_N", during.f_cmd_W.z()}, {"pen_rise_m", during.p_WT.z() - z_before_m},
                      {"confirmed", confirmed ? nlohmann::json(*confirmed) : nlohmann::json(nullptr)}}},
      {"verdicts", verdictsJson(judgement)},
      {"verdict", std::string(servo::verdictName(judgement.overall))},
      {"ok", ok},
  };
  if (opt.json) {
    printJson(json);
  } else {
    std::cout << fmt::format("loop        {} clock, {} ticks, {} overruns, {} faults, {} link faults, {} stalls\n",
                             servo::loopClockName(loop.clock()), c.ticks.load(), c.overruns.load(), c.faults.load(),
                             c.link_faults.load(), c.stalls.load())
              << fmt::format("jitter      period error p50 {:.1f} µs, p99 {:.1f} µs, max {:.1f} µs\n",
                             us(pe.percentile_ns(0.5)), us(pe.percentile_ns(0.99)), us(pe.max_ns()))
              << fmt::format("force test  {:.3f} N commanded upward; the pen rose {:.2f} mm; person: {}\n",
                             during.f_cmd_W.z(), (during.p_WT.z() - z_before_m) * 1e3,
                             confirmed ? (*confirmed ? "felt it" : "did NOT feel it") : "not asked")
              << (force_ok ? ""
                           : fmt::format("failed      the {} N test force was not reached{}\n", opt.force_N,
                                         c.faults.load() > 0   ? " (the safety path latched a fault)"
                                         : c.stalls.load() == 0 ? " within 5 s"
                                                                : " within 5 s (each stall restarts the force ramp)"))
              << (device->faultReason().empty() ? "" : "fault       " + device->faultReason() + "\n")
              << "\n"
              << verdictsText(judgement)
              << (!ok                                           ? "check FAILED\n"
                  : judgement.overall == servo::Verdict::kWarn ? "check passed with warnings (WARN: this computer's "
                                                                  "scheduling or load; docs/realtime.md)\n"
                                                                : "check passed\n");
  }
  return ok ? kOk : kRuntimeFailure;
}

}  // namespace

void registerDevicesCommands(CLI::App& app) {
  auto* devices = app.add_subcommand("devices",
                                     "List the device kinds and URIs hattr accepts (sim://, plugin:, udp://) and the "
                                     "plugins it finds; check a device; serve one over the network");
  devices->alias("device");
  devices->callback([devices] {
    if (devices->get_subcommands().empty()) std::cout << kindsText();
  });

  auto opt = std::make_shared<CheckOptions>();
  auto* check = devices->add_subcommand(
      "check", "Open a device, report its limits and rate, measure its loop's jitter, and apply a gentle force that "
               "the person holding it confirms (exit 1 if anything fails)");
  check->add_option("uri", opt->uri, "Device URI (see `hattr devices`)")->required();
  check->add_option("--seconds", opt->seconds, "Jitter measurement [s]")->check(CLI::Range(0.1, 60.0))->capture_default_str();
  check->add_option("--force-N", opt->force_N, "The gentle test force, upward [N]")
      ->check(CLI::Range(0.01, 2.0))
      ->capture_default_str();
  check->add_option("--rate", opt->rate_hz, "Servo rate [Hz] (default: the device's nominal rate)")
      ->check(CLI::Range(1.0, 10000.0));
  check->add_flag("--no-confirm", opt->no_confirm,
                  "Do not ask the person (unattended runs, simulated devices): the force test is judged by what "
                  "was commanded");
  check->add_flag("--json", opt->json,
                  "Print JSON: device, clocking, loop_clock, rate_hz, limits, capabilities, period_error_us, ticks, "
                  "overruns, faults, link_faults, stalls, force_test {commanded_N, pen_rise_m, confirmed}, verdicts [{figure, value, "
                  "unit, verdict, rule}], verdict, ok");
  check->callback([opt] {
    if (runCheck(*opt) != kOk) throw Error("the device check failed (see above)");
  });
  registerDeviceServeCommands(*devices);
}

}  // namespace hattr::cli
