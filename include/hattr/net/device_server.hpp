#pragma once
/// The device server behind `hattr device serve`: runs next to the hardware (or a simulated
/// pen) with its own servo loop and safety path at the device's rate, streams the pen's state
/// to one client at a time and applies the forces that client commands (udp:// devices,
/// hattr::device::UdpDevice). Protocol, handshake and timeouts: docs/protocol.md.
///
/// The session (handshake, checks, timeouts) is wire::ResponderLinkSession, the one the mentoring
/// leader uses too. A fault the server's safety path latched (a device error) stays latched
/// across sessions: no client can clear it; restart the server.
///
/// Threads: the constructor and start()/stop() are setup code (they throw hattr::Error /
/// InputError); the network work happens inside the servo tick (a GuidanceController stage:
/// non-blocking socket calls, no allocation, no locks); counters may be read from any thread.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

#include "hattr/device/device.hpp"
#include "hattr/core/guidance_controller.hpp"
#include "hattr/wire/keys.hpp"
#include "hattr/wire/packet.hpp"
#include "hattr/wire/udp_socket.hpp"
#include "hattr/servo/servo_loop.hpp"

namespace hattr::net {

struct DeviceServerConfig {
  std::string device_uri = "sim://pen";                 ///< the local device (any hattr device URI)
  std::string listen = "127.0.0.1:0";                   ///< HOST:PORT to listen on (port 0: any free port)
  wire::AuthKey key;                             ///< the shared key (wire::readKeyFile)
  double rate_hz = 0.0;                                 ///< servo rate [Hz]; 0: the device's nominal rate
  std::chrono::nanoseconds command_timeout{10'000'000};   ///< zero force without a COMMAND for this long
  std::chrono::nanoseconds session_timeout{500'000'000};  ///< end a session silent for this long
  servo::RealtimeSettings realtime;
};

/// What the server did. Plain numbers (a snapshot).
struct DeviceServerStats {
  std::uint64_t sessions = 0;          ///< sessions opened
  std::uint64_t session_timeouts = 0;  ///< sessions ended by silence
  std::uint64_t byes = 0;              ///< sessions ended by the client's BYE
  std::uint64_t busy_refusals = 0;     ///< HELLOs answered BUSY
  std::uint64_t cookies_sent = 0;      ///< HELLOs answered with a COOKIE (no valid cookie yet)
  std::uint64_t commands_applied = 0;  ///< COMMANDs accepted (the newest of each tick is applied)
  std::uint64_t command_timeouts = 0;  ///< times the force went to zero for want of a COMMAND
  std::uint64_t states_sent = 0;       ///< STATE packets sent (one a tick while a session lives)
  wire::DropCounts drops{};            ///< datagrams dropped, by wire::DropReason
  std::uint64_t ticks = 0;             ///< the server's servo loop (servo::LiveCounters)
  std::uint64_t overruns = 0;          ///< ticks that missed their deadline
  std::uint64_t stalls = 0;  ///< gaps in the loop's ticks beyond its watchdog (a host that held it up)
  std::uint64_t faults = 0;            ///< safety faults the loop latched
};

class DeviceServer {
 public:
  /// Opens the device and the socket, builds the loop (not started). Throws InputError for
  /// a bad URI or address, hattr::Error when the port cannot be had.
  explicit DeviceServer(DeviceServerConfig config);
  /// Stops (if running) and says BYE to a live client.
  ~DeviceServer();
  DeviceServer(const DeviceServer&) = delete;
  DeviceServer& operator=(const DeviceServer&) = delete;

  /// Starts the servo loop on its real-time thread (or the device's clock). Throws
  /// hattr::Error if real-time settings are required and refused.
  void start();
  /// Stops the loop, commands zero force, says BYE to a live client. Idempotent.
  void stop();

  /// Where it listens (the port chosen when the configuration said 0).
  [[nodiscard]] const wire::UdpEndpoint& endpoint() const noexcept { return endpoint_; }
  [[nodiscard]] DeviceServerStats stats() const;
  /// True while a client's session is live. Any thread.
  [[nodiscard]] bool sessionLive() const noexcept;
  /// The force of the newest accepted COMMAND [N] (before the safety path). Any thread.
  [[nodiscard]] Vec3 commandedForce() const noexcept;
  /// The force last written to the device, after the safety path [N]. Any thread.
  [[nodiscard]] Vec3 appliedForce() const noexcept;

  /// The loop, for tests that tick it by hand (tick(now) while not started) and for reports.
  [[nodiscard]] servo::ServoLoop& loop() noexcept;
  /// The local device.
  [[nodiscard]] device::Device& device() noexcept;

  class Impl;

 private:
  std::unique_ptr<Impl> impl_;
  wire::UdpEndpoint endpoint_;
};

}  // namespace hattr::net
