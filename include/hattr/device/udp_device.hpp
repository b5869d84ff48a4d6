#pragma once
/// The network device: a pen served by `hattr device serve` on another machine (or
/// process), opened as udp://HOST:PORT?key=FILE[&hold_ms=5][&timeout_s=1]. The server runs
/// its own servo loop and safety path next to the hardware; this client sends the force
/// (and, for a simulated pen, the simulated hand's command) once per tick and reads the
/// newest pen state. Protocol: docs/protocol.md (include/hattr/wire/).
///
/// The session (handshake, checks) is wire::InitiatorLinkSession, the one the mentoring follower
/// uses too.
///
/// Threads: the constructor (handshake) blocks up to timeout_s and throws; read() and
/// write() run on the servo thread (non-blocking socket calls, no allocation, no locks);
/// faultReason() and the counters of linkStats() (and link(), the Device interface's view of
/// them) may be read from any thread.

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

#include "hattr/device/device.hpp"
#include "hattr/device/device_uri.hpp"
#include "hattr/device/hand.hpp"
#include "hattr/wire/packet.hpp"
#include "hattr/wire/udp_socket.hpp"

namespace hattr::device {

/// The parameters of a udp:// URI.
struct UdpDeviceParams {
  wire::UdpEndpoint server;              ///< HOST:PORT (IPv4 or localhost)
  std::filesystem::path key_file;       ///< key=FILE (required): the shared key (hattr device keygen)
  double hold_s = 0.005;                ///< hold_ms: bridge missing states this long, then disconnected
  double handshake_timeout_s = 1.0;     ///< timeout_s: how long open waits for the server
};

/// Reads and checks a udp:// URI's target and keys. Unknown keys and out-of-range values
/// throw InputError naming the key, what is accepted and what was given.
UdpDeviceParams udpDeviceParams(const DeviceUri& uri);


class UdpDevice final : public Device {
 public:
  /// Opens the session: HELLO, COOKIE, HELLO, WELCOME (or BUSY), first STATE. Throws
  /// InputError when the server refuses (busy), does not answer within the timeout (also
  /// what a wrong key looks like), speaks another protocol version, or the key file is bad.
  /// `hand` (may be null, must outlive the device) rides along in every COMMAND to drive a
  /// simulated pen on the server.
  UdpDevice(const UdpDeviceParams& params, std::string uri_text, HandScript* hand);
  /// Says BYE.
  ~UdpDevice() override;
  UdpDevice(const UdpDevice&) = delete;
  UdpDevice& operator=(const UdpDevice&) = delete;

  /// Reads what arrived (within a time budget), keeps the newest authentic STATE; bridges
  /// missing states for hold_ms counted from the newest state's arrival, then reports
  /// kDisconnected (and says hello again every 50 ms).
  DeviceStatus read(std::chrono::nanoseconds now, PenState& out) noexcept override;
  /// Sends a COMMAND with the force [N, W] (and the hand's command at the last read time).
  DeviceStatus write(const Vec3& f_on_pen_W) noexcept override;
  const DeviceLimits& limits() const noexcept override;
  DeviceCapabilities capabilities() const noexcept override;
  const std::string& uri() const noexcept override;
  DeviceClocking clocking() const noexcept override { return DeviceClocking::kHostRealTime; }
  std::string faultReason() const override;

  /// The server's servo rate [Hz] (from WELCOME).
  [[nodiscard]] double serverRate_hz() const noexcept;
  /// A snapshot. Counters: any thread; histograms: only while the loop is stopped.
  [[nodiscard]] LinkStats linkStats() const;
  /// The link's statistics and the server's rate (Device::link).
  [[nodiscard]] std::optional<DeviceLink> link() const override { return DeviceLink{linkStats(), serverRate_hz()}; }

  class Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

/// Opens udp://HOST:PORT?key=FILE[&hold_ms=..][&timeout_s=..] (see UdpDevice). Throws
/// InputError for a bad URI or key file, a busy server or no answer.
std::unique_ptr<Device> openUdpDevice(const DeviceUri& uri, std::string_view uri_text, HandScript* hand);

/// Help text for udp:// URIs and their keys.
std::string udpDeviceHelp();

}  // namespace hattr::device
