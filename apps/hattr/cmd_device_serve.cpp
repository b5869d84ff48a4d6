// hattr device serve | keygen: serve a local device (hardware or a simulated pen) to one
// network client at a time (udp://HOST:PORT?key=FILE), and make the shared key.

#include <csignal>
#include <iostream>
#include <thread>

#include <fmt/format.h>

#include "cli_common.hpp"
#include "hattr/net/device_server.hpp"
#include "hattr/ops/json.hpp"
#include "hattr/wire/packet.hpp"

namespace hattr::cli {
namespace {

struct ServeOptions {
  std::string device = "sim://pen";
  std::string listen;
  std::string key;
  double rate_hz = 0.0;
  double command_timeout_ms = 10.0;
  double session_timeout_ms = 500.0;
  double seconds = 0.0;
  std::string realtime = "try";
  int cpu = -1;
  bool json = false;
};

struct KeygenOptions {
  std::string out;
  bool force = false;
};

volatile std::sig_atomic_t g_stop_signal = 0;
extern "C" void onStopSignal(int signal_number) { g_stop_signal = signal_number; }

nlohmann::json statsJson(const net::DeviceServerStats& s) {
  const nlohmann::json drops = ops::dropsJson(s.drops);
  return {{"sessions", s.sessions},         {"session_timeouts", s.session_timeouts},
          {"byes", s.byes},                 {"busy_refusals", s.busy_refusals},
          {"commands_applied", s.commands_applied}, {"command_timeouts", s.command_timeouts},
          {"states_sent", s.states_sent},   {"drops", drops},
          {"ticks", s.ticks},               {"overruns", s.overruns},
          {"stalls", s.stalls},             {"faults", s.faults}};
}

// Serves until SIGINT/SIGTERM (or --seconds), then prints what happened.
void runServe(const ServeOptions& opt) {
  net::DeviceServerConfig config;
  config.device_uri = opt.device;
  config.listen = opt.listen;
  config.key = wire::readKeyFile(opt.key);
  config.rate_hz = opt.rate_hz;
  config.command_timeout = std::chrono::nanoseconds(static_cast<std::int64_t>(opt.command_timeout_ms * 1e6));
  config.session_timeout = std::chrono::nanoseconds(static_cast<std::int64_t>(opt.session_timeout_ms * 1e6));
  config.realtime = {.policy = servo::parseRealtimePolicy(opt.realtime), .cpu = opt.cpu};
  net::DeviceServer server(config);

  struct sigaction action {};
  action.sa_handler = onStopSignal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);

  server.start();
  std::cout << "listening on " << server.endpoint().text() << std::endl;
  const auto start = std::chrono::steady_clock::now();
  const auto limit = std::chrono::duration<double>(opt.seconds);
  // Say on stderr when a client's session opens and ends (stdout stays the report).
  std::uint64_t sessions_told = 0;
  bool live_told = false;
  while (g_stop_signal == 0 && (opt.seconds <= 0.0 || std::chrono::steady_clock::now() - start < limit)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    const bool live = server.sessionLive();
    const std::uint64_t sessions = server.stats().sessions;
    if (sessions != sessions_told && live) std::cerr << fmt::format("hattr: session {} opened", sessions) << std::endl;
    if (live_told && !live) std::cerr << "hattr: session ended" << std::endl;
    sessions_told = live ? sessions : sessions_told;
    live_told = live;
  }
  server.stop();

  const net::DeviceServerStats s = server.stats();
  const double rate_hz = 1e9 / static_cast<double>(server.loop().period().count());
  if (opt.json) {
    nlohmann::json json = statsJson(s);
    json["device"] = opt.device;
    json["listen"] = server.endpoint().text();
    json["rate_hz"] = rate_hz;
    printJson(json);
    return;
  }
  std::string drops;
  for (std::size_t r = 0; r < wire::kDropReasonCount; ++r) {
    drops += fmt::format("{}{} {}", drops.empty() ? "" : ", ",
                         wire::dropReasonName(static_cast<wire::DropReason>(r)), s.drops[r]);
  }
  std::cout << fmt::format("served {} at {} Hz on {}\n", opt.device, rate_hz, server.endpoint().text())
            << fmt::format("sessions {} (ended: {} by bye, {} by silence), busy refusals {}\n", s.sessions, s.byes,
                           s.session_timeouts, s.busy_refusals)
            << fmt::format("commands applied {}, command timeouts {}, states sent {}\n", s.commands_applied,
                           s.command_timeouts, s.states_sent)
            << fmt::format("drops: {}\nticks {}, overruns {}, stalls {}, faults {}\n", drops, s.ticks, s.overruns, s.stalls, s.faults);
}

void runKeygen(const KeygenOptions& opt) {
  wire::writeKeyFile(opt.out, wire::randomKey(), opt.force);
  std::cout << fmt::format("wrote a new key to {} (mode 0600); give the same file to the server (--key) and the "
                           "client (udp://HOST:PORT?key=FILE)\n",
                           opt.out);
}

}  // namespace

void registerDeviceServeCommands(CLI::App& devices) {
  auto opt = std::make_shared<ServeOptions>();
  auto* serve = devices.add_subcommand(
      "serve",
      "Serve a local device to one network client at a time (udp://HOST:PORT?key=FILE): its own servo loop and "
      "safety path at the device's rate, streaming the pen and applying the forces received");
  serve->add_option("--device", opt->device, "Device URI to serve (see `hattr devices`)")->capture_default_str();
  serve->add_option("--listen", opt->listen, "HOST:PORT to listen on (IPv4 or localhost; port 0: any free port)")
      ->required();
  serve->add_option("--key", opt->key, "Shared key file (64 hex characters, mode 0600; `hattr device keygen`)")->required();
  serve->add_option("--rate", opt->rate_hz, "Servo rate [Hz] (0: the device's nominal rate)")
      ->check(CLI::Range(0.0, 10000.0))
      ->capture_default_str();
  serve->add_option("--command-timeout-ms", opt->command_timeout_ms,
                    "Zero the force when no command arrived for this long [ms]")
      ->check(CLI::Range(0.5, 1000.0))
      ->capture_default_str();
  serve->add_option("--session-timeout-ms", opt->session_timeout_ms,
                    "End a session when the client is silent for this long [ms]")
      ->check(CLI::Range(10.0, 60000.0))
      ->capture_default_str();
  serve->add_option("--seconds", opt->seconds, "Stop after this long [s] (0: until SIGINT/SIGTERM)")
      ->check(CLI::Range(0.0, 1e7))
      ->capture_default_str();
  serve->add_option("--realtime", opt->realtime, "SCHED_FIFO + mlockall: require, try or skip")
      ->check(CLI::IsMember({"require", "try", "skip"}))
      ->capture_default_str();
  serve->add_option("--cpu", opt->cpu, "Pin the servo thread to this CPU (-1: no pinning)")->capture_default_str();
  serve->add_flag("--json", opt->json,
                  "At exit print JSON: sessions, session_timeouts, byes, busy_refusals, commands_applied, "
                  "command_timeouts, states_sent, drops {reason: count}, ticks, overruns, stalls, faults");
  serve->callback([opt] { runServe(*opt); });

  auto keygen_opt = std::make_shared<KeygenOptions>();
  auto* keygen = devices.add_subcommand("keygen", "Write a fresh random key for `device serve` and udp:// (mode 0600)");
  keygen->add_option("--out", keygen_opt->out, "Key file to write")->required();
  keygen->add_flag("--force", keygen_opt->force, "Replace the file if it exists");
  keygen->callback([keygen_opt] { runKeygen(*keygen_opt); });
}

}  // namespace hattr::cli
