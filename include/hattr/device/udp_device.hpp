#pragma once
/// The network device: a pen served by `hattr device serve` on another machine (or
/// process), opened as udp://HOST:PORT?key=FILE[&hold_ms=5][&timeout_s=1]. The server runs
/// its own servo loop and safety path next to the hardware; this client sends the force
/// (and, for a simulated pen, the simulated hand's command) once per tick and reads the
/// newest pen state. Protocol: docs/protocol.md (include/hattr/device/net_protocol.hpp).
///
/// Threads: the constructor (handshake) blocks up to timeout_s and throws; read() and
/// write() run on the servo thread (non-blocking socket calls, no allocation, no locks);
/// faultReason() and the counters of linkStats() may be read from any thread.

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

#include "hattr/core/histogram.hpp"
#include "hattr/device/device.hpp"
#include "hattr/device/device_uri.hpp"
#include "hattr/device/hand.hpp"
#include "hattr/device/net_protocol.hpp"
#include "hattr/device/udp_socket.hpp"

namespace hattr::device {

/// The parameters of a udp:// URI.
struct UdpDeviceParams {
  net::UdpEndpoint server;              ///< HOST:PORT (IPv4 or localhost)
  std::filesystem::path key_file;       ///< key=FILE (required): the shared key (hattr device keygen)
  double hold_s = 0.005;                ///< hold_ms: bridge missing states this long, then disconnected
  double handshake_timeout_s = 1.0;     ///< timeout_s: how long open waits for the server
};

/// Reads and checks a udp:// URI's target and keys. Unknown keys and out-of-range values
/// throw InputError naming the key, what is accepted and what was given.
UdpDeviceParams udpDeviceParams(const DeviceUri& uri);

/// What the link did, for servo-check and reports.
struct LinkStats {
  DurationHistogram rtt;         ///< network round trip: COMMAND sent → STATE received, minus the server's hold [ns]
  DurationHistogram state_age;   ///< age of the state read() returned: server sampling → client use [ns]
  std::int64_t clock_offset_ns = 0;  ///< server clock − client clock, from the lowest-RTT exchange (NTP-style)
  std::uint64_t commands_sent = 0;
  std::uint64_t states_received = 0;  ///< accepted STATE packets
  std::uint64_t states_lost = 0;      ///< gaps in the STATE sequence
  std::uint64_t states_late = 0;      ///< arrived after a newer one: dropped, never used
  std::uint64_t held_reads = 0;       ///< reads that bridged with the previous state (no new one)
  std::uint64_t disconnected_reads = 0;
  std::uint64_t reconnects = 0;       ///< new sessions after the first
  std::array<std::uint64_t, net::kDropReasonCount> drops{};  ///< by net::DropReason
};

class UdpDevice final : public Device {
 public:
  /// Opens the session: HELLO, WELCOME (or BUSY), first STATE. Throws InputError when the
  /// server refuses (busy), does not answer within the timeout (also what a wrong key
  /// looks like) or the key file is bad. `hand` (may be null, must outlive the device)
  /// rides along in every COMMAND to drive a simulated pen on the server.
  UdpDevice(const UdpDeviceParams& params, std::string uri_text, HandScript* hand);
  /// Says BYE.
  ~UdpDevice() override;
  UdpDevice(const UdpDevice&) = delete;
  UdpDevice& operator=(const UdpDevice&) = delete;

  /// Drains the socket (bounded), keeps the newest authentic STATE; bridges missing
  /// states for hold_ms, then reports kDisconnected (and says hello again every 50 ms).
  DeviceStatus read(std::chrono::nanoseconds now, PenState& out) noexcept override;
  /// Sends a COMMAND with the force [N, W] (and the hand's command at the last read time).
  DeviceStatus write(const Vec3& f_on_pen_W) noexcept override;
  const DeviceLimits& limits() const noexcept override { return welcome_.limits; }
  DeviceCapabilities capabilities() const noexcept override { return welcome_.capabilities; }
  const std::string& uri() const noexcept override { return uri_; }
  DeviceClocking clocking() const noexcept override { return DeviceClocking::kHostRealTime; }
  std::string faultReason() const override;

  /// The server's servo rate [Hz] (from WELCOME).
  [[nodiscard]] double serverRate_hz() const noexcept { return welcome_.rate_hz; }
  /// A snapshot. Counters: any thread; histograms: only while the loop is stopped.
  [[nodiscard]] LinkStats linkStats() const;

 private:
  enum class Fault : int {
    kNone, kLinkLost, kServerClosed, kServerBusy, kServerDeviceFault, kServerDeviceDisconnected, kServerSafetyFault,
    kServerLimitsChanged
  };

  void sendHello(std::int64_t now_ns) noexcept;
  void drain() noexcept;
  void handle(const net::Packet& packet, const net::Received& rx) noexcept;
  void setFault(Fault fault, double gap_ms) noexcept;
  std::uint64_t bump(std::atomic<std::uint64_t>& counter) noexcept {
    return counter.fetch_add(1, std::memory_order_relaxed);
  }

  UdpDeviceParams params_;
  std::string uri_;
  HandScript* hand_;
  net::AuthKey key_;
  net::UdpSocket socket_;
  net::RandomStream random_;
  std::int64_t hold_ns_;

  // Session (servo thread after the handshake).
  net::WelcomePayload welcome_;
  std::uint64_t session_id_ = 0;
  std::uint64_t send_sequence_ = 0;
  net::SequenceCheck state_sequence_;
  std::uint64_t lost_previous_sessions_ = 0;
  net::Nonce pending_nonce_{};
  bool hello_pending_ = false;
  std::int64_t last_hello_ns_ = 0;
  bool server_closed_ = false;
  bool server_busy_ = false;
  bool limits_changed_ = false;  // a reconnection found a device of other limits

  // The newest state and the link's timing.
  net::StatePayload state_;
  std::int64_t state_sent_ns_ = 0;       // its sender time (server clock)
  std::int64_t state_arrival_ns_ = -1;   // its arrival (client clock); -1: none yet
  std::int64_t last_read_ns_ = -1;
  std::int64_t resume_ns_ = 0;
  std::uint64_t used_state_sequence_ = 0;
  std::uint64_t last_echo_sequence_ = 0;
  double loop_time_s_ = 0.0;
  std::int64_t best_rtt_ns_ = -1;
  std::int64_t offset_candidate_ns_ = 0;
  std::uint64_t offset_window_ = 0;
  net::PacketBuffer rx_buffer_{};
  net::PacketBuffer tx_buffer_{};

  // Readable from other threads.
  std::atomic<int> fault_{0};
  std::atomic<double> fault_gap_ms_{0.0};
  std::atomic<std::int64_t> clock_offset_ns_{0};
  std::atomic<std::uint64_t> commands_sent_{0};
  std::atomic<std::uint64_t> states_received_{0};
  std::atomic<std::uint64_t> held_reads_{0};
  std::atomic<std::uint64_t> disconnected_reads_{0};
  std::atomic<std::uint64_t> reconnects_{0};
  std::atomic<std::uint64_t> states_lost_{0};
  net::DropCounters drops_;
  DurationHistogram rtt_;
  DurationHistogram state_age_;
};

/// Opens udp://HOST:PORT?key=FILE[&hold_ms=..][&timeout_s=..] (see UdpDevice). Throws
/// InputError for a bad URI or key file, a busy server or no answer.
std::unique_ptr<Device> openUdpDevice(const DeviceUri& uri, std::string_view uri_text, HandScript* hand);

/// Help text for udp:// URIs and their keys.
std::string udpDeviceHelp();

}  // namespace hattr::device
