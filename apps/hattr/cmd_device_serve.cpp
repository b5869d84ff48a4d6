// hattr device serve | keygen: serve a local device (hardware or a simulated pen) to one
// network client at a time (udp://HOST:PORT?key=FILE), and make the shared key.

#include <csignal>
#include <iostream>
#include <thread>

#include <fmt/format.h>

#include "cli_common.hpp"
#include "hattr/ops/device_serve.hpp"
#include "hattr/wire/keys.hpp"
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

// Serves until SIGINT/SIGTERM (or --seconds), then prints what happened.
void runServe(const ServeOptions& opt) {
  // SIGINT/SIGTERM stop the server once it serves (during the set-up they end the process).
  const auto catchStopSignals = [] {
    struct sigaction action {};
    action.sa_handler = onStopSignal;
    sigemptyset(&action.sa_mask);
    sigaction(SIGINT, &action, nullptr);
    sigaction(SIGTERM, &action, nullptr);
  };
  // Sessions opening and ending are said on stderr (stdout stays the report).
  const ops::DeviceServeResult served = ops::serveDevice(
      {.device = opt.device,
       .listen = opt.listen,
       .key_file = opt.key,
       .rate_hz = opt.rate_hz,
       .command_timeout_s = opt.command_timeout_ms * 1e-3,
       .session_timeout_s = opt.session_timeout_ms * 1e-3,
       .realtime = {.policy = servo::parseRealtimePolicy(opt.realtime), .cpu = opt.cpu},
       .seconds = opt.seconds,
       .listening =
           [&](const std::string& endpoint) {
             catchStopSignals();
             std::cout << "listening on " << endpoint << std::endl;
           },
       .session_opened = [](std::uint64_t n) { std::cerr << fmt::format("hattr: session {} opened", n) << std::endl; },
       .session_ended = [] { std::cerr << "hattr: session ended" << std::endl; },
       .stop_requested = [] { return g_stop_signal != 0; }});
  if (opt.json) return printJson(served.toJson());
  const net::DeviceServerStats& s = served.stats;
  std::string drops;
  for (std::size_t r = 0; r < wire::kDropReasonCount; ++r) {
    drops += fmt::format("{}{} {}", drops.empty() ? "" : ", ",
                         wire::dropReasonName(static_cast<wire::DropReason>(r)), s.drops[r]);
  }
  std::cout << fmt::format("served {} at {} Hz on {}\n", opt.device, served.rate_hz, served.listen)
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
