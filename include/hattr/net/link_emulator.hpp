#pragma once
/// A network link emulator: one direction of a link with delay, jitter, loss, reordering and
/// duplication, seeded, so a test of live mentoring or of the network device sees the same
/// bad network every run. Used in-process (in simulated or real time: the caller passes the
/// time) and in front of a real UDP socket on loopback (LinkRelay). No allocation after
/// construction: datagrams wait in a fixed pool.
///
/// The model, per datagram sent at time t: lost with probability `loss`; else delivered at
/// t + delay + U(0, jitter), plus `reorder_extra` with probability `reorder` (so it arrives
/// after later ones); and, with probability `duplicate`, delivered a second time
/// U(0, jitter) later. Jitter alone also reorders datagrams spaced closer than the jitter.

#include <array>
#include <atomic>
#include <cstdint>
#include <random>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "hattr/wire/packet.hpp"
#include "hattr/wire/udp_socket.hpp"

namespace hattr::net {

struct LinkConditions {
  double delay_s = 0.0;          ///< one-way base delay [s]
  double jitter_s = 0.0;         ///< extra delay, uniform in [0, jitter] [s]
  double loss = 0.0;             ///< probability a datagram is lost
  double reorder = 0.0;          ///< probability a datagram is held back by reorder_extra_s
  double reorder_extra_s = 0.002;
  double duplicate = 0.0;        ///< probability a datagram arrives twice
  std::uint64_t seed = 1;
  /// Throws InputError naming the field for a negative, non-finite or (probabilities) > 1 value.
  void validate() const;
};

/// What a link did. Plain numbers.
struct LinkStats {
  std::uint64_t sent = 0;
  std::uint64_t delivered = 0;
  std::uint64_t lost = 0;
  std::uint64_t duplicated = 0;
  std::uint64_t reordered = 0;   ///< delivered after a datagram sent later
  std::uint64_t overflow = 0;    ///< dropped because the pool was full
};

class LinkEmulator {
 public:
  /// `capacity`: datagrams in flight at most (a full pool drops and counts). Throws InputError.
  explicit LinkEmulator(const LinkConditions& conditions, std::size_t capacity = 4096);

  /// Takes a datagram sent at `now_ns` (any clock, the same for receive). noexcept, no allocation.
  void send(std::span<const std::uint8_t> datagram, std::int64_t now_ns) noexcept;
  /// The earliest datagram due by `now_ns`, copied into `out` (its size in `size`); false if none.
  bool receive(std::int64_t now_ns, std::span<std::uint8_t> out, std::size_t& size) noexcept;
  /// When the next datagram falls due (INT64_MAX when none waits).
  [[nodiscard]] std::int64_t nextDue() const noexcept;

  [[nodiscard]] LinkStats stats() const noexcept { return stats_; }
  [[nodiscard]] const LinkConditions& conditions() const noexcept { return conditions_; }

 private:
  struct InFlight {
    std::int64_t due_ns = 0;
    std::uint64_t order = 0;  ///< send order, to count reordering
    std::size_t size = 0;
    wire::PacketBuffer bytes{};
  };
  void enqueue(std::span<const std::uint8_t> datagram, std::int64_t due_ns, std::uint64_t order) noexcept;

  LinkConditions conditions_;
  std::vector<InFlight> pool_;   // the first count_ entries are in flight
  std::size_t count_ = 0;
  std::uint64_t next_order_ = 0;
  std::uint64_t newest_delivered_ = 0;
  bool delivered_any_ = false;
  std::mt19937_64 random_;
  LinkStats stats_;
};

/// A UDP relay on loopback with an emulator in each direction: datagrams sent to `listen`
/// go to `forward` as if over the emulated link, and the answers come back to the last
/// sender the same way. Runs a thread of its own (real time). For tests and demos of the
/// network device and of mentoring under delay.
class LinkRelay {
 public:
  /// Binds `listen` (port 0: any free port); throws InputError / hattr::Error.
  LinkRelay(const std::string& listen, const std::string& forward, const LinkConditions& to_forward,
            const LinkConditions& to_sender);
  ~LinkRelay();
  LinkRelay(const LinkRelay&) = delete;
  LinkRelay& operator=(const LinkRelay&) = delete;

  [[nodiscard]] const wire::UdpEndpoint& endpoint() const noexcept { return endpoint_; }
  /// Stops the thread (idempotent).
  void stop();
  /// What each direction did. Only after stop().
  [[nodiscard]] LinkStats forwardStats() const;
  [[nodiscard]] LinkStats backStats() const;

 private:
  void run();

  wire::UdpSocket front_;  // where the sender sends
  wire::UdpSocket back_;   // connected to `forward`
  wire::UdpEndpoint endpoint_;
  wire::UdpEndpoint sender_{};
  bool has_sender_ = false;
  LinkEmulator to_forward_;
  LinkEmulator to_sender_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace hattr::net
