// hattr servo-check: runs the real-time loop with the full pipeline on a (simulated) device
// next to a bare sleep loop measured in the same run, and reports both.

#include <algorithm>
#include <atomic>
#include <chrono>
#include <exception>
#include <functional>
#include <iostream>
#include <thread>

#include <fmt/format.h>

#include "cli_common.hpp"
#include "hattr/core/error.hpp"
#include "hattr/device/device_uri.hpp"
#include "hattr/device/udp_device.hpp"
#include "hattr/render/paper_renderer.hpp"
#include "hattr/servo/servo_loop.hpp"

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

nlohmann::json percentilesUs(const DurationHistogram& h) {
  const auto us = [](std::int64_t ns) { return static_cast<double>(ns) * 1e-3; };
  return {{"p50", us(h.percentile_ns(0.50))}, {"p99", us(h.percentile_ns(0.99))},
          {"p99_9", us(h.percentile_ns(0.999))}, {"max", us(h.max_ns())}, {"count", h.count()}};
}

// The network link of a udp:// device: round trip, state age, loss, late packets, drops.
nlohmann::json linkJson(const device::LinkStats& s) {
  nlohmann::json drops = nlohmann::json::object();
  for (std::size_t r = 0; r < wire::kDropReasonCount; ++r) {
    drops[std::string(wire::dropReasonName(static_cast<wire::DropReason>(r)))] = s.drops[r];
  }
  const double expected = static_cast<double>(s.states_received + s.states_lost);
  return {{"rtt_us", percentilesUs(s.rtt)},
          {"state_age_us", percentilesUs(s.state_age)},
          {"clock_offset_us", static_cast<double>(s.clock_offset_ns) * 1e-3},
          {"commands_sent", s.commands_sent},
          {"states_received", s.states_received},
          {"states_lost", s.states_lost},
          {"loss", expected > 0.0 ? static_cast<double>(s.states_lost) / expected : 0.0},
          {"states_late", s.states_late},
          {"held_reads", s.held_reads},
          {"disconnected_reads", s.disconnected_reads},
          {"reconnects", s.reconnects},
          {"drops", drops}};
}

servo::RealtimePolicy parsePolicy(const std::string& text) {
  if (text == "require") return servo::RealtimePolicy::kRequire;
  if (text == "try") return servo::RealtimePolicy::kTry;
  return servo::RealtimePolicy::kSkip;
}

nlohmann::json reportJson(const servo::RealtimeReport& r) {
  return {{"fifo", r.fifo}, {"memory_locked", r.memory_locked}, {"pinned", r.pinned},
          {"timer_slack_minimal", r.timer_slack_minimal}, {"notes", r.notes}};
}

/// Draws `progress` (the seconds passed, at most `seconds`) every 0.1 s until `done()` or
/// `deadline`.
void waitShowingProgress(Progress& progress, double seconds, const std::function<bool()>& done,
                         std::chrono::steady_clock::time_point deadline = std::chrono::steady_clock::time_point::max()) {
  const auto begin = std::chrono::steady_clock::now();
  for (auto now = begin; !done() && now < deadline; now = std::chrono::steady_clock::now()) {
    std::this_thread::sleep_until(std::min(deadline, now + std::chrono::milliseconds(100)));
    const double passed = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
    progress.update(std::min(passed, seconds));
  }
}

/// Runs the check; returns its overall verdict (the figures' worst).
servo::Verdict runServoCheck(const ServoCheckOptions& opt) {
  servo::RealtimeSettings realtime{.policy = parsePolicy(opt.realtime),
                                   .cpu = opt.cpu,
                                   .final_spin = std::chrono::nanoseconds(static_cast<std::int64_t>(opt.spin_us * 1e3))};
  const auto duration = std::chrono::nanoseconds(static_cast<std::int64_t>(opt.seconds * 1e9));

  // The platform's floor first: the same sleeps with nothing to do. On a terminal it is
  // measured on its own thread while this one draws the progress line; otherwise here.
  Progress progress("", 0, "s");
  servo::RealtimeReport floor_report;
  DurationHistogram floor;
  if (Progress::onTerminal()) {
    progress.stage("servo-check 1/2: the bare sleep loop (floor)", opt.seconds);
    std::exception_ptr floor_error;
    std::atomic<bool> floor_done{false};
    {
      std::jthread floor_thread([&] {  // joined at the end of the block, whatever happens
        try {
          floor = servo::measureSleepFloor(opt.rate_hz, duration, realtime, &floor_report);
        } catch (...) {
          floor_error = std::current_exception();
        }
        floor_done.store(true, std::memory_order_release);
      });
      waitShowingProgress(progress, opt.seconds, [&] { return floor_done.load(std::memory_order_acquire); });
    }
    if (floor_error) std::rethrow_exception(floor_error);
  } else {
    floor = servo::measureSleepFloor(opt.rate_hz, duration, realtime, &floor_report);
  }

  // Then the full pipeline: a hand writing circles on the paper through the device.
  render::WorldConfig world = worldConfigOrDefault(opt.world);
  const std::vector<std::string> clamps = clampWorldToDevice(world, opt.device, opt.rate_hz);
  for (const auto& c : clamps) std::cerr << "hattr: world clamped: " << c << '\n';
  render::PaperRenderer paper(world.paper, render::buildRelief(world.relief));
  device::CircleHand hand(Vec3::Zero(), 0.015, 1.0, 1.0);
  const auto device = device::openDevice(opt.device, &hand);
  servo::ServoLoop loop(*device, servo::ServoConfig{.rate_hz = opt.rate_hz, .realtime = realtime});
  loop.setWorld(&paper);
  std::atomic<bool> done{false};
  std::uint64_t consumed = 0;
  std::thread consumer([&] {  // drains samples like the recorder does
    TickSample s;
    while (!done.load(std::memory_order_acquire)) {
      while (loop.samples().tryPop(s)) ++consumed;
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    while (loop.samples().tryPop(s)) ++consumed;
  });
  loop.start();
  if (Progress::onTerminal()) {
    progress.stage("servo-check 2/2: the servo loop", opt.seconds);
    waitShowingProgress(progress, opt.seconds, [] { return false; }, std::chrono::steady_clock::now() + duration);
  } else {
    std::this_thread::sleep_for(duration);
  }
  loop.stop();
  progress.finish();
  done = true;
  consumer.join();

  const auto& c = loop.counters();
  const double floor_p99 = static_cast<double>(floor.percentile_ns(0.99));
  const double loop_p99 = static_cast<double>(loop.periodError().percentile_ns(0.99));
  nlohmann::json json = {
      {"rate_hz", opt.rate_hz},
      {"seconds", opt.seconds},
      {"device", opt.device},
      {"world", opt.world.empty() ? "defaults" : opt.world},
      {"world_clamps", clamps},
      {"realtime", reportJson(loop.realtimeReport())},
      {"floor", {{"period_error_us", percentilesUs(floor)}}},
      {"loop",
       {{"period_error_us", percentilesUs(loop.periodError())},
        {"tick_compute_us", percentilesUs(loop.tickCompute())},
        {"ticks", c.ticks.load()},
        {"samples_consumed", consumed},
        {"overruns", c.overruns.load()},
        {"dropped_samples", c.dropped_samples.load()},
        {"faults", c.faults.load()},
        {"stalls", c.stalls.load()},
        {"link_faults", c.link_faults.load()},
        {"disconnected_ticks", c.disconnected_ticks.load()}}},
      {"ratio_p99", floor_p99 > 0.0 ? loop_p99 / floor_p99 : 0.0},
  };
  const auto* udp = dynamic_cast<const device::UdpDevice*>(device.get());
  servo::LoopJudgement judgement = servo::judgeLoop(loop);
  if (udp != nullptr) {
    json["link"] = linkJson(udp->linkStats());
    json["link"]["server_rate_hz"] = udp->serverRate_hz();
    json["link"]["fault"] = udp->faultReason();
    servo::judgeLink(udp->linkStats(), judgement);
  }
  json["verdicts"] = verdictsJson(judgement);
  json["verdict"] = std::string(servo::verdictName(judgement.overall));
  if (opt.json) {
    printJson(json);
    return judgement.overall;
  }
  const auto row = [](const char* name, const nlohmann::json& p) {
    return fmt::format("{:<22} {:>9.2f} {:>9.2f} {:>9.2f} {:>9.2f}\n", name, p["p50"].get<double>(),
                       p["p99"].get<double>(), p["p99_9"].get<double>(), p["max"].get<double>());
  };
  std::cout << fmt::format("servo-check: {} Hz for {} s on {}\n", opt.rate_hz, opt.seconds, opt.device)
            << fmt::format("real time: SCHED_FIFO {}, mlockall {}, pinned {}{}\n\n", loop.realtimeReport().fifo ? "yes" : "no",
                           loop.realtimeReport().memory_locked ? "yes" : "no", loop.realtimeReport().pinned ? "yes" : "no",
                           loop.realtimeReport().notes.empty() ? "" : " (" + loop.realtimeReport().notes + ")")
            << fmt::format("{:<22} {:>9} {:>9} {:>9} {:>9}\n", "[µs]", "p50", "p99", "p99.9", "max")
            << row("floor period error", json["floor"]["period_error_us"])
            << row("loop period error", json["loop"]["period_error_us"])
            << row("loop tick compute", json["loop"]["tick_compute_us"])
            << fmt::format("\nticks {}, overruns {}, dropped samples {}, faults {}, stalls {}\nratio p99 (loop/floor) {:.2f}\n",
                           c.ticks.load(), c.overruns.load(), c.dropped_samples.load(), c.faults.load(), c.stalls.load(),
                           json["ratio_p99"].get<double>());
  if (udp != nullptr) {
    const nlohmann::json& link = json["link"];
    std::string drops;
    for (const auto& [reason, count] : link["drops"].items()) {
      if (count.get<std::uint64_t>() > 0) drops += fmt::format("{}{} {}", drops.empty() ? "" : ", ", reason, count.get<std::uint64_t>());
    }
    std::cout << fmt::format("\nlink to {} (server at {} Hz)\n", opt.device, link["server_rate_hz"].get<double>())
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
                             c.link_faults.load(), c.disconnected_ticks.load());
    if (!link["fault"].get<std::string>().empty()) std::cout << "last link fault: " << link["fault"].get<std::string>() << '\n';
  }
  std::cout << "\n" << verdictsText(judgement);
  return judgement.overall;
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
