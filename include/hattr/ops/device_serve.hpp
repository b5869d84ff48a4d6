#pragma once
/// Serving a local device to one network client at a time (`hattr device serve`; docs/
/// protocol.md) as one library call: the device opened behind the wire protocol's responder,
/// its own servo loop and safety path at the device's rate, until the time is up or the caller
/// asks it to stop; then what happened.
///
/// Threads: blocks, polling every 10 ms; the callbacks run on the calling thread.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>

#include <nlohmann/json.hpp>

#include "hattr/net/device_server.hpp"

namespace hattr::ops {

struct DeviceServeOptions {
  std::string device = "sim://pen";      ///< the local device (any hattr device URI)
  std::string listen;                    ///< HOST:PORT (port 0: any free port)
  std::filesystem::path key_file;        ///< the shared key (`hattr device keygen`)
  double rate_hz = 0.0;                  ///< servo rate [Hz]; 0: the device's nominal rate
  double command_timeout_s = 0.010;      ///< zero force without a COMMAND for this long [s]
  double session_timeout_s = 0.500;      ///< end a session silent for this long [s]
  servo::RealtimeSettings realtime;
  double seconds = 0.0;                  ///< stop after this long [s]; 0: only when stop_requested
  /// Once the socket is bound and the loop runs: where it listens.
  std::function<void(const std::string& endpoint)> listening;
  /// A client's session opened (its number, from 1), or the live one ended.
  std::function<void(std::uint64_t session)> session_opened;
  std::function<void()> session_ended;
  /// Asked every 10 ms: true stops the server (a signal, a button).
  std::function<bool()> stop_requested;
};

struct DeviceServeResult {
  std::string device;
  std::string listen;                    ///< the bound endpoint
  double rate_hz = 0.0;                  ///< the loop's rate
  net::DeviceServerStats stats;
  /// {device, listen, rate_hz, sessions, session_timeouts, byes, busy_refusals, commands_applied,
  /// command_timeouts, states_sent, drops {reason: count}, ticks, overruns, stalls, faults}.
  [[nodiscard]] nlohmann::json toJson() const;
};

/// Serves until the time is up or stop_requested(). Throws InputError for a bad device URI,
/// address or key file, hattr::Error when the port cannot be had.
DeviceServeResult serveDevice(const DeviceServeOptions& options);

}  // namespace hattr::ops
