#pragma once
/// A non-blocking IPv4 UDP socket for the network device and its server: kernel arrival
/// timestamps (converted to CLOCK_MONOTONIC), no allocation in receive() and send().
/// Opening and binding are setup code and throw; receive()/send() are servo-thread safe.

#include <cstdint>
#include <span>
#include <string>
#include <string_view>

namespace hattr::device::net {

/// An IPv4 address and port, host byte order.
struct UdpEndpoint {
  std::uint32_t address = 0;
  std::uint16_t port = 0;
  [[nodiscard]] std::string text() const;  ///< "127.0.0.1:5000"
  friend bool operator==(const UdpEndpoint&, const UdpEndpoint&) = default;
};

/// Parses "HOST:PORT": HOST an IPv4 address or "localhost" (127.0.0.1), PORT in
/// [min_port, 65535]. Throws InputError starting with `where` and saying what is accepted.
[[nodiscard]] UdpEndpoint parseUdpEndpoint(std::string_view text, std::string_view where, int min_port = 1);

/// What receive() found.
enum class ReceiveStatus { kPacket, kNone, kRefused };

struct Received {
  std::size_t size = 0;             ///< bytes of the datagram (may exceed the buffer: then it is cut)
  UdpEndpoint from;
  std::int64_t arrival_ns = 0;      ///< kernel arrival time on CLOCK_MONOTONIC [ns]
};

class UdpSocket {
 public:
  /// A socket bound to `local` (port 0: any free port). Throws hattr::Error on failure.
  [[nodiscard]] static UdpSocket bound(const UdpEndpoint& local);
  /// A socket connected to `peer` (the kernel then delivers only the peer's datagrams).
  [[nodiscard]] static UdpSocket connected(const UdpEndpoint& peer);

  UdpSocket(UdpSocket&& other) noexcept;
  UdpSocket& operator=(UdpSocket&& other) noexcept;
  UdpSocket(const UdpSocket&) = delete;
  UdpSocket& operator=(const UdpSocket&) = delete;
  ~UdpSocket();

  [[nodiscard]] UdpEndpoint localEndpoint() const;

  /// One datagram if one is waiting (never blocks). kRefused: the peer's port was
  /// unreachable (connected sockets; ICMP). Servo-thread safe.
  ReceiveStatus receive(std::span<std::uint8_t> buffer, Received& out) noexcept;
  /// Sends without blocking; false if the kernel refused or would block.
  bool send(std::span<const std::uint8_t> datagram) noexcept;
  bool sendTo(std::span<const std::uint8_t> datagram, const UdpEndpoint& to) noexcept;
  /// Waits up to `timeout_ns` for a datagram (setup code only: blocks). True if one is ready.
  bool waitReadable(std::int64_t timeout_ns) const noexcept;

 private:
  explicit UdpSocket(int fd) noexcept : fd_(fd) {}
  int fd_ = -1;
};

}  // namespace hattr::device::net
