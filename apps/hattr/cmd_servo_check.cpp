// hattr servo-check: runs the real-time loop with the full pipeline on a (simulated) device
// next to a bare sleep loop measured in the same run, and reports both.

#include <chrono>
#include <iostream>

#include <fmt/format.h>

#include "cli_common.hpp"
#include "hattr/core/error.hpp"
#include "hattr/core/units.hpp"
#include "hattr/ops/servo_check.hpp"

namespace hattr::cli {
namespace {

struct ServoCheckOptions {
  double rate_hz = 1000.0;
  double seconds = 5.0;
  std::string device = "sim://pen";
  std::string world;
  std::string realtime = "try";
  int cpu = -1;
  double spin_us = 0.0;
  bool json = false;
};

/// Prints the check for people: the real time got, the three timing rows, the counters, the
/// link's figures for a device behind one, the verdicts.
void printServoCheck(const ops::ServoCheckResult& r) {
  const nlohmann::json json = r.toJson();
  const auto row = [](const char* name, const nlohmann::json& p) {
    return fmt::format("{:<22} {:>9.2f} {:>9.2f} {:>9.2f} {:>9.2f}\n", name, p["p50"].get<double>(),
                       p["p99"].get<double>(), p["p99_9"].get<double>(), p["max"].get<double>());
  };
  const servo::LoopFigures& f = r.figures;
  std::cout << fmt::format("servo-check: {} Hz for {} s on {}\n", r.options.rate_hz, r.options.seconds, r.options.device)
            << fmt::format("real time: SCHED_FIFO {}, mlockall {}, pinned {}{}\n\n", r.realtime.fifo ? "yes" : "no",
                           r.realtime.memory_locked ? "yes" : "no", r.realtime.pinned ? "yes" : "no",
                           r.realtime.notes.empty() ? "" : " (" + r.realtime.notes + ")")
            << fmt::format("{:<22} {:>9} {:>9} {:>9} {:>9}\n", "[µs]", "p50", "p99", "p99.9", "max")
            << row("floor period error", json["floor"]["period_error_us"])
            << row("loop period error", json["loop"]["period_error_us"])
            << row("loop tick compute", json["loop"]["tick_compute_us"])
            << fmt::format("\nticks {}, overruns {}, dropped samples {}, faults {}, stalls {}\nratio p99 (loop/floor) {:.2f}\n",
                           f.ticks, f.overruns, f.dropped_samples, f.faults, f.stalls, r.ratioP99());
  if (r.link) {
    const nlohmann::json& link = json["link"];
    std::string drops;
    for (const auto& [reason, count] : link["drops"].items()) {
      if (count.get<std::uint64_t>() > 0) drops += fmt::format("{}{} {}", drops.empty() ? "" : ", ", reason, count.get<std::uint64_t>());
    }
    std::cout << fmt::format("\nlink to {} (server at {} Hz)\n", r.options.device, r.link->server_rate_hz)
              << fmt::format("{:<22} {:>9} {:>9} {:>9} {:>9}\n", "[µs]", "p50", "p99", "p99.9", "max")
              << row("round trip", link["rtt_us"]) << row("state age", link["state_age_us"])
              << fmt::format("commands sent {}, states received {}, lost {} ({:.3f} %), late {} (dropped, none applied)\n",
                             link["commands_sent"].get<std::uint64_t>(), link["states_received"].get<std::uint64_t>(),
                             link["states_lost"].get<std::uint64_t>(), 100.0 * link["loss"].get<double>(),
                             link["states_late"].get<std::uint64_t>())
              << fmt::format("held reads {}, disconnected reads {}, reconnects {}, clock offset {:.1f} µs\n",
                             link["held_reads"].get<std::uint64_t>(), link["disconnected_reads"].get<std::uint64_t>(),
                             link["reconnects"].get<std::uint64_t>(), link["clock_offset_us"].get<double>())
              << fmt::format("drops: {}\nloop: link faults {}, disconnected ticks {}\n", drops.empty() ? "none" : drops,
                             f.link_faults, r.disconnected_ticks);
    if (!r.link_fault.empty()) std::cout << "last link fault: " << r.link_fault << '\n';
  }
  std::cout << "\n" << verdictsText(r.judgement);
}

/// Runs the check (the library's), showing progress on a terminal; returns the overall verdict.
servo::Verdict runServoCheck(const ServoCheckOptions& opt) {
  ops::ServoCheckOptions options{
      .rate_hz = opt.rate_hz,
      .seconds = opt.seconds,
      .device = opt.device,
      .world = opt.world,
      .realtime = {.policy = servo::parseRealtimePolicy(opt.realtime),
                   .cpu = opt.cpu,
                   .final_spin = std::chrono::nanoseconds(units::secondsToNanoseconds(opt.spin_us * 1e-6))}};
  Progress progress("", 0, "s");
  int shown = 0;  // the run the progress line shows
  if (Progress::onTerminal()) {
    options.progress = [&](int run, double seconds) {
      if (run != shown) {
        progress.stage(run == 1 ? "servo-check 1/2: the bare sleep loop (floor)" : "servo-check 2/2: the servo loop",
                       opt.seconds);
        shown = run;
      }
      progress.update(seconds);
    };
  }
  const ops::ServoCheckResult result = ops::runServoCheck(options);
  progress.finish();
  for (const auto& c : result.world_clamps) std::cerr << "hattr: world clamped: " << c << '\n';
  if (opt.json) {
    printJson(result.toJson());
  } else {
    printServoCheck(result);
  }
  return result.judgement.overall;
}

}  // namespace

void registerServoCheckCommand(CLI::App& app) {
  auto opt = std::make_shared<ServoCheckOptions>();
  auto* cmd = app.add_subcommand("servo-check",
                                 "Run the real-time servo loop (full pipeline) next to a bare sleep loop and report "
                                 "period error, tick compute time, overruns, drops and faults, each with a verdict "
                                 "(PASS, WARN, FAIL; exit 1 on FAIL)");
  cmd->add_option("--rate", opt->rate_hz, "Servo rate [Hz]")->check(CLI::Range(1.0, 10000.0))->capture_default_str();
  cmd->add_option("--seconds", opt->seconds,
                  "Duration of each of the two runs, the bare sleep loop (floor) and then the servo loop: the "
                  "check takes twice this [s]")
      ->check(CLI::Range(0.01, 3600.0))
      ->capture_default_str();
  cmd->add_option("--device", opt->device, "Device URI (see `hattr devices`)")->capture_default_str();
  cmd->add_option("--world", opt->world, "World (paper) configuration JSON (default: the built-in defaults)");
  cmd->add_option("--realtime", opt->realtime, "SCHED_FIFO + mlockall: require, try or skip")
      ->check(CLI::IsMember({"require", "try", "skip"}))
      ->capture_default_str();
  cmd->add_option("--cpu", opt->cpu, "Pin the servo thread to this CPU (-1: no pinning)")->capture_default_str();
  cmd->add_option("--spin-us", opt->spin_us, "Busy-wait this long before each deadline [µs]")
      ->check(CLI::Range(0.0, 1000.0))
      ->capture_default_str();
  cmd->add_flag("--json", opt->json,
                "Print JSON: loop and floor {period_error_us {p50, p99, p99_9, max}}, loop {tick_compute_us, overruns, "
                "dropped_samples, faults}, ratio_p99; for udp:// devices also link {rtt_us, state_age_us, clock_offset_us, "
                "commands_sent, states_received, states_lost, loss, states_late, held_reads, "
                "disconnected_reads, reconnects, drops {reason: count}}; verdicts [{figure, value, unit, verdict, "
                "rule}] and verdict (PASS, WARN or FAIL: docs/realtime.md)");
  cmd->callback([opt] {
    if (runServoCheck(*opt) == servo::Verdict::kFail) {
      throw Error("servo-check: FAIL: a figure failed its threshold (see the verdicts; docs/realtime.md)");
    }
  });
}

}  // namespace hattr::cli
