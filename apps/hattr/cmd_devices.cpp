// hattr devices (alias: device): the device kinds and URIs hattr accepts, the plugins it finds,
// and `devices check URI`, which a lab runs on a new device: limits, rate, a jitter
// measurement and a gentle force the person confirms. `device serve` and `device keygen` are
// in cmd_device_serve.cpp.

#include <iostream>

#include <fmt/format.h>
#include <unistd.h>

#include "cli_common.hpp"
#include "hattr/core/error.hpp"
#include "hattr/device/device_uri.hpp"
#include "hattr/device/plugin_device.hpp"
#include "hattr/ops/device_check.hpp"

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

std::string kindsText() {
  std::string text = device::deviceUriHelp();
  const auto plugins = device::findPlugins();
  text += "\nplugins found (plugin:NAME, or plugin:/path/libX.so):\n";
  if (plugins.empty()) text += "  none (search path: $HATTR_PLUGIN_PATH, then the prefix's LIBDIR/hattr/plugins: `hattr paths`)\n";
  for (const auto& p : plugins) text += fmt::format("  {:<14} {}\n    {}\n", p.name, p.description, p.path);
  text += "\nCheck a device before a study: hattr devices check URI (docs/devices.md).\n";
  return text;
}

/// Asks the person a yes/no question on the terminal; nullopt when nobody answers (no input).
std::optional<bool> askPerson(const std::string& question) {
  std::cerr << question << " [y/n] " << std::flush;
  std::string answer;
  if (!std::getline(std::cin, answer)) return std::nullopt;
  return !answer.empty() && (answer[0] == 'y' || answer[0] == 'Y');
}

// The library's check, described before it runs and shown after.
int runCheck(const CheckOptions& opt) {
  ops::DeviceCheckOptions options{.uri = opt.uri, .seconds = opt.seconds, .force_N = opt.force_N, .rate_hz = opt.rate_hz};
  if (!opt.json) {
    options.opened = [&](const ops::DeviceDescription& d) {
      std::cout << fmt::format("device      {}\nclock       {}\nrate        {} Hz\nforce       {} N continuous, {} N peak\n"
                               "stiffness   {} N/m max\n",
                               d.uri, ops::clockingName(d.clocking), d.rate_hz, d.limits.continuous_force_N,
                               d.limits.peak_force_N, d.limits.max_stiffness_N_per_m)
                << std::flush;
    };
  }
  if (!opt.no_confirm) {
    options.announce = [](const std::string& notice) { std::cerr << notice << '\n'; };
    options.confirm = [] { return askPerson("Did you feel a gentle upward push?"); };
  }
  const ops::DeviceCheckResult r = ops::runDeviceCheck(options);
  if (opt.json) {
    printJson(r.toJson());
    return r.ok() ? kOk : kRuntimeFailure;
  }
  const servo::LoopFigures& f = r.figures;
  const auto us = [](std::int64_t ns) { return static_cast<double>(ns) * 1e-3; };
  std::cout << fmt::format("loop        {} clock, {} ticks, {} overruns, {} faults, {} link faults, {} stalls\n",
                           servo::loopClockName(r.loop_clock), f.ticks, f.overruns, f.faults, f.link_faults, f.stalls)
            << fmt::format("jitter      period error p50 {:.1f} µs, p99 {:.1f} µs, max {:.1f} µs\n",
                           us(r.period_error.percentile_ns(0.5)), us(r.period_error.percentile_ns(0.99)),
                           us(r.period_error.max_ns()))
            << fmt::format("force test  {:.3f} N commanded {}; the pen moved {:.2f} mm that way; person: {}\n",
                           r.commanded_N, r.force_direction, r.pen_rise_m * 1e3,
                           r.confirmed ? (*r.confirmed ? "felt it" : "did NOT feel it") : "not asked")
            << (r.force_reached ? ""
                                : fmt::format("failed      the {} N test force was not reached{}\n", opt.force_N,
                                              f.faults > 0   ? " (the safety path latched a fault)"
                                              : f.stalls == 0 ? " within 5 s"
                                                              : " within 5 s (each stall restarts the force ramp)"))
            << (r.fault_reason.empty() ? "" : "fault       " + r.fault_reason + "\n")
            << "\n"
            << verdictsText(r.judgement)
            << (!r.ok()                                           ? "check FAILED\n"
                : r.judgement.overall == servo::Verdict::kWarn ? "check passed with warnings (WARN: this computer's "
                                                                  "scheduling or load; docs/realtime.md)\n"
                                                                : "check passed\n");
  return r.ok() ? kOk : kRuntimeFailure;
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
  check->add_option("--force-N", opt->force_N, "The gentle test force [N]: up, or on a planar pen away from the writer")
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
