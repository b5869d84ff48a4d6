#pragma once
/// A non-blocking IPv4 UDP socket for the wire protocol: kernel arrival timestamps on
/// CLOCK_MONOTONIC, a receive buffer sized for a burst, no allocation in receive() and send().
/// Opening and binding are setup code and throw; receive()/send() are servo-thread safe.

#include <cstdint>
#include <span>
#include <string>
#include <string_view>

namespace hattr::wire {

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
  std::int64_t arrival_ns = 0;      ///< arrival time on CLOCK_MONOTONIC [ns] (see UdpSocket::receive)
};

/// The arrival on CLOCK_MONOTONIC of a datagram the kernel stamped at `stamp_real_ns`
/// (CLOCK_REALTIME), received when the clocks read `mono_ns` and `real_ns`: `mono_ns` less the
/// datagram's age, unless the real-time clock stepped since the previous receive (the offset
/// real − mono moved more than UdpSocket::kMaxClockStep from `offset_ns`) or the age is
/// negative; then `mono_ns`. `offset_ns` (0: no previous receive) becomes this receive's offset.
[[nodiscard]] std::int64_t monotonicArrival(std::int64_t mono_ns, std::int64_t real_ns, std::int64_t stamp_real_ns,
                                            std::int64_t& offset_ns) noexcept;

class UdpSocket {
 public:
  /// The receive buffer asked of the kernel [bytes]: room for a burst of some thousand
  /// datagrams (the kernel caps it at net.core.rmem_max; docs/protocol.md).
  static constexpr int kReceiveBufferBytes = 4 << 20;
  /// A change of (CLOCK_REALTIME − CLOCK_MONOTONIC) beyond this is a step of the real-time
  /// clock [ns] (slewing by NTP moves it by microseconds a second at most).
  static constexpr std::int64_t kMaxClockStep = 1'000'000;

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
  /// True for a socket made by connected().
  [[nodiscard]] bool isConnected() const noexcept { return connected_; }

  /// One datagram if one is waiting (never blocks). kRefused: the peer's port was
  /// unreachable (connected sockets; ICMP). The arrival time is on CLOCK_MONOTONIC: the
  /// kernel stamps datagrams only by CLOCK_REALTIME, so its age is measured on that clock and
  /// taken back from CLOCK_MONOTONIC now; when the real-time clock stepped since the previous
  /// receive (the offset between the clocks moved more than kMaxClockStep), the age is not
  /// believed and the arrival is the time of this call. Servo-thread safe.
  ReceiveStatus receive(std::span<std::uint8_t> buffer, Received& out) noexcept;
  /// Sends without blocking; false if the kernel refused or would block.
  bool send(std::span<const std::uint8_t> datagram) noexcept;
  bool sendTo(std::span<const std::uint8_t> datagram, const UdpEndpoint& to) noexcept;
  /// Waits up to `timeout_ns` for a datagram (setup code only: blocks). True if one is ready.
  bool waitReadable(std::int64_t timeout_ns) const noexcept;

 private:
  explicit UdpSocket(int fd) noexcept : fd_(fd) {}
  int fd_ = -1;
  bool connected_ = false;
  std::int64_t clock_offset_ns_ = 0;  // CLOCK_REALTIME − CLOCK_MONOTONIC at the previous receive; 0: none yet
};

}  // namespace hattr::wire
