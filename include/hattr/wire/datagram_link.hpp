#pragma once
/// One datagram transport for a wire session: a UDP socket, or an emulated link in process
/// (hattr::net::EmulatedLinkPair). Servo-thread functions: noexcept, no allocation, never
/// block.

#include <cstdint>
#include <span>

#include "hattr/wire/packet.hpp"
#include "hattr/wire/udp_socket.hpp"

namespace hattr::wire {

class DatagramLink {
 public:
  virtual ~DatagramLink() = default;
  /// The next datagram that has arrived by time `now_ns` (the session's clock), copied into
  /// `buffer`; its size (which may exceed the buffer: then it was cut), sender and arrival
  /// time (on the session's clock) in `out`. False when none is waiting.
  virtual bool receive(std::int64_t now_ns, PacketBuffer& buffer, Received& out) noexcept = 0;
  /// Sends a datagram to `to` at time `now_ns`; false if it could not be sent.
  virtual bool send(std::int64_t now_ns, std::span<const std::uint8_t> datagram, const UdpEndpoint& to) noexcept = 0;
  /// True once the peer's host refused a datagram (ICMP port unreachable; connected sockets).
  [[nodiscard]] virtual bool refused() const noexcept { return false; }
};

/// A UDP socket as a DatagramLink. Its clock is either the socket's (CLOCK_MONOTONIC, kernel
/// arrival stamps: the device server and the udp:// client) or the caller's loop time (the
/// arrival is the `now_ns` of the receive: the mentoring stations, whose times are loop times).
class UdpDatagramLink final : public DatagramLink {
 public:
  enum class Clock { kMonotonic, kLoop };
  /// A bound socket sends to whom it is asked; a connected one only to its peer (the kernel
  /// then also delivers only the peer's datagrams).
  UdpDatagramLink(UdpSocket socket, Clock clock) : socket_(std::move(socket)), clock_(clock) {}
  bool receive(std::int64_t now_ns, PacketBuffer& buffer, Received& out) noexcept override;
  bool send(std::int64_t now_ns, std::span<const std::uint8_t> datagram, const UdpEndpoint& to) noexcept override;
  [[nodiscard]] bool refused() const noexcept override { return refused_; }
  [[nodiscard]] UdpEndpoint localEndpoint() const { return socket_.localEndpoint(); }
  /// Waits up to `timeout_ns` for a datagram (setup code only: blocks).
  bool waitReadable(std::int64_t timeout_ns) const noexcept { return socket_.waitReadable(timeout_ns); }

 private:
  UdpSocket socket_;
  Clock clock_;
  bool refused_ = false;
};

}  // namespace hattr::wire
