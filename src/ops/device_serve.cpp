#include "hattr/ops/device_serve.hpp"

#include <chrono>
#include <thread>

#include "hattr/ops/json.hpp"
#include "hattr/wire/keys.hpp"

namespace hattr::ops {

nlohmann::json DeviceServeResult::toJson() const {
  const net::DeviceServerStats& s = stats;
  return {{"device", device},
          {"listen", listen},
          {"rate_hz", rate_hz},
          {"sessions", s.sessions},
          {"session_timeouts", s.session_timeouts},
          {"byes", s.byes},
          {"busy_refusals", s.busy_refusals},
          {"commands_applied", s.commands_applied},
          {"command_timeouts", s.command_timeouts},
          {"states_sent", s.states_sent},
          {"drops", dropsJson(s.drops)},
          {"ticks", s.ticks},
          {"overruns", s.overruns},
          {"stalls", s.stalls},
          {"faults", s.faults}};
}

DeviceServeResult serveDevice(const DeviceServeOptions& options) {
  net::DeviceServerConfig config;
  config.device_uri = options.device;
  config.listen = options.listen;
  config.key = wire::readKeyFile(options.key_file);
  config.rate_hz = options.rate_hz;
  config.command_timeout = std::chrono::round<std::chrono::nanoseconds>(std::chrono::duration<double>(options.command_timeout_s));
  config.session_timeout = std::chrono::round<std::chrono::nanoseconds>(std::chrono::duration<double>(options.session_timeout_s));
  config.realtime = options.realtime;
  net::DeviceServer server(config);
  server.start();
  if (options.listening) options.listening(server.endpoint().text());

  // Until the time is up or the caller stops it, saying when a client's session opens and ends.
  const auto start = std::chrono::steady_clock::now();
  const auto limit = std::chrono::duration<double>(options.seconds);
  std::uint64_t sessions_told = 0;
  bool live_told = false;
  while (!(options.stop_requested && options.stop_requested()) &&
         (options.seconds <= 0.0 || std::chrono::steady_clock::now() - start < limit)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    const bool live = server.sessionLive();
    const std::uint64_t sessions = server.stats().sessions;
    if (sessions != sessions_told && live && options.session_opened) options.session_opened(sessions);
    if (live_told && !live && options.session_ended) options.session_ended();
    sessions_told = live ? sessions : sessions_told;
    live_told = live;
  }
  server.stop();
  return {.device = options.device,
          .listen = server.endpoint().text(),
          .rate_hz = 1e9 / static_cast<double>(server.loop().period().count()),
          .stats = server.stats()};
}

}  // namespace hattr::ops
