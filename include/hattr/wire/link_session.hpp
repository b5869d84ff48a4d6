#pragma once
/// The one implementation of the wire protocol's link sessions (docs/protocol.md; "link
/// session" beside a study's sessions and the study store's tables): the handshake,
/// the session rules and the checks every received datagram passes, for the three roles that
/// speak it. The initiator (the udp:// client, the mentoring follower) says HELLO; the
/// responder (the device server, the mentoring leader) answers with a stateless COOKIE, then
/// with WELCOME or BUSY; then each side streams its data packets (COMMAND / STATE, or PEER)
/// until a BYE or silence ends the session.
///
/// Both ends are fixed-size state machines over a DatagramLink, with every time given by the
/// caller (the session's clock: CLOCK_MONOTONIC, or a station's loop time).
///
/// Threads: construction is setup code (throws); pump(), connect(), send(), close() and
/// takeData() run on one thread, the servo thread (noexcept, no allocation, no locks, no
/// blocking); stats(), live() and generation() may be read from any thread.

#include <array>
#include <atomic>
#include <cstdint>

#include "hattr/wire/datagram_link.hpp"
#include "hattr/wire/keys.hpp"
#include "hattr/wire/packet.hpp"

namespace hattr::wire {

/// The times a session keeps [ns].
struct LinkSessionTiming {
  std::int64_t session_timeout_ns = 500'000'000;  ///< a session silent this long is over
  std::int64_t hello_retry_ns = 100'000'000;      ///< the initiator says HELLO again while unanswered
  /// A pump stops reading after this much work (real time) and leaves the rest for the next
  /// one: a flood cannot hold the tick up, and the newest authentic data packet of each pump
  /// is the one acted on.
  std::int64_t drain_budget_ns = 250'000;
};

/// A responder's cookies change every kCookieEpochNs; a HELLO's cookie is good in its epoch
/// and the next, so a recorded HELLO opens nothing after at most two epochs [ns].
inline constexpr std::int64_t kCookieEpochNs = 1'000'000'000;
/// Handshake packets one pump verifies at most; more are dropped unverified (kRateLimited), so
/// a flood of forged HELLOs costs a pump a system call each, not a MAC, and the session's
/// data packets behind them are reached within the drain budget.
inline constexpr int kMaxHandshakesPerPump = 4;
/// Sessions a responder remembers the HELLO nonces of (for the two epochs a cookie lives);
/// with that many opened within two epochs, it refuses more with BUSY until one ages out.
inline constexpr std::size_t kNonceMemory = 64;

/// What one end of a link session did. A snapshot of plain numbers.
struct LinkSessionStats {
  std::uint64_t sessions = 0;        ///< sessions opened
  std::uint64_t timeouts = 0;        ///< sessions ended by silence
  std::uint64_t byes_received = 0;   ///< sessions the other side ended
  std::uint64_t busy = 0;            ///< responder: HELLOs refused with BUSY; initiator: BUSYs received
  std::uint64_t cookies = 0;         ///< responder: COOKIEs sent; initiator: COOKIEs received
  std::uint64_t data_received = 0;   ///< authentic data packets of a live session accepted
  std::uint64_t data_lost = 0;       ///< gaps in their sequence, over all sessions
  DropCounts drops{};                ///< datagrams dropped, by DropReason
};

/// What the two ends share: the data path, the checks, the counters.
class LinkSession {
 public:
  LinkSession(const LinkSession&) = delete;
  LinkSession& operator=(const LinkSession&) = delete;
  virtual ~LinkSession() = default;

  /// Reads what has arrived (within the drain budget), runs the handshake, keeps the newest
  /// authentic data packet, and ends a session silent for the session timeout.
  void pump(std::int64_t now_ns) noexcept;
  /// The newest data packet accepted since the last call, and its arrival; false if none.
  bool takeData(Packet& out, std::int64_t& arrival_ns) noexcept;
  /// Sends a data packet (or BYE) of the live session to the other side; false without one.
  bool send(const Payload& payload, std::int64_t now_ns) noexcept;
  /// Says BYE and ends the live session (if any).
  void close(std::int64_t now_ns) noexcept;

  /// A session is open (any thread).
  [[nodiscard]] bool live() const noexcept { return live_flag_.load(std::memory_order_acquire); }
  /// An authentic data packet of the live session has arrived: the other side holds the key.
  [[nodiscard]] bool confirmed() const noexcept { return live_ && confirmed_; }
  /// Sessions opened so far (any thread): a change means a new session.
  [[nodiscard]] std::uint64_t generation() const noexcept { return sessions_.load(std::memory_order_acquire); }
  /// When the other side was last heard (the arrival of its newest accepted packet).
  [[nodiscard]] std::int64_t lastHeard_ns() const noexcept { return last_heard_ns_; }
  /// The other side's address (the responder's, or the live session's initiator).
  [[nodiscard]] const UdpEndpoint& peer() const noexcept { return peer_; }
  [[nodiscard]] LinkSessionStats stats() const noexcept;
  /// Sessions the other side ended with a BYE (any thread; cheaper than stats() on a tick).
  [[nodiscard]] std::uint64_t byesReceived() const noexcept { return byes_.load(std::memory_order_relaxed); }
  /// Responder: HELLOs refused with BUSY; initiator: BUSYs received (any thread).
  [[nodiscard]] std::uint64_t busyCount() const noexcept { return busy_.load(std::memory_order_relaxed); }
  /// Counts a drop the caller found (a datagram cut by its buffer is counted here already).
  void countDrop(DropReason reason) noexcept { drops_.count(reason); }

 protected:
  LinkSession(const AuthKey& shared, Role role, PacketType data_in, DatagramLink& link, const LinkSessionTiming& timing);

  /// A handshake packet (authentic, of a type this end's role takes) arrived.
  virtual void onHandshake(const Packet& packet, const Received& rx, std::int64_t now_ns) noexcept = 0;
  /// The handshake types this end accepts.
  [[nodiscard]] virtual bool isHandshake(PacketType type) const noexcept = 0;
  /// After each pump's reading; `went_silent`: the live session just ended by silence.
  virtual void afterDrain(std::int64_t now_ns, bool went_silent) noexcept = 0;
  /// A BYE of the live session arrived (the session has ended).
  virtual void onBye() noexcept {}
  /// The live session ended (any way: a BYE either way, silence, close()).
  virtual void onEnded() noexcept {}

  /// Opens session `id` with `peer` (counts it; resets the sequences).
  void open(std::uint64_t id, const UdpEndpoint& peer, std::int64_t now_ns) noexcept;
  /// Ends the live session without a word (silence, a BYE heard, a new one).
  void end() noexcept;
  /// Encodes and sends a packet with this end's key.
  void sendPacket(const Packet& packet, const UdpEndpoint& to, std::int64_t now_ns) noexcept;
  [[nodiscard]] std::uint64_t nextSequence() noexcept { return ++send_sequence_; }
  void bump(std::atomic<std::uint64_t>& counter) noexcept { counter.fetch_add(1, std::memory_order_relaxed); }

  DirectionKeys keys_;
  DatagramLink& link_;
  LinkSessionTiming timing_;
  RandomStream random_;
  DropCounters drops_;
  bool live_ = false;
  bool confirmed_ = false;
  std::uint64_t id_ = 0;
  UdpEndpoint peer_{};
  std::int64_t last_heard_ns_ = 0;
  SequenceCheck received_;

  std::atomic<std::uint64_t> sessions_{0};
  std::atomic<std::uint64_t> timeouts_{0};
  std::atomic<std::uint64_t> byes_{0};
  std::atomic<std::uint64_t> busy_{0};
  std::atomic<std::uint64_t> cookies_{0};

 private:
  void receive(const Received& rx, std::int64_t now_ns) noexcept;
  void receiveSessionPacket(const PacketHeader& header, const Received& rx) noexcept;

  PacketType data_in_;
  int handshakes_this_pump_ = 0;
  std::uint64_t send_sequence_ = 0;
  PacketBuffer rx_buffer_{};
  PacketBuffer tx_buffer_{};
  Packet newest_{};
  std::int64_t newest_arrival_ns_ = 0;
  bool fresh_ = false;
  std::uint64_t lost_before_ = 0;  // sequence gaps of ended sessions

  std::atomic<bool> live_flag_{false};
  std::atomic<std::uint64_t> data_received_{0};
  std::atomic<std::uint64_t> data_lost_{0};
};

/// The end that says HELLO: the udp:// client (data in: STATE) and the mentoring follower (PEER).
class InitiatorLinkSession final : public LinkSession {
 public:
  enum class State : int {
    kIdle,        ///< no session, no attempt
    kConnecting,  ///< HELLO sent (again every hello_retry), waiting for COOKIE / WELCOME / BUSY
    kLive,        ///< welcomed: a session
    kRefused,     ///< the responder answered BUSY
    kClosed,      ///< the responder said BYE
    kSilent,      ///< the session ended: nothing heard for the session timeout
  };

  /// Throws hattr::Error if libsodium cannot start.
  InitiatorLinkSession(const AuthKey& shared, PacketType data_in, DatagramLink& link, const UdpEndpoint& responder,
                       const LinkSessionTiming& timing);

  /// A new attempt: a fresh nonce, HELLO now and again every hello_retry until answered. A
  /// live session stays usable until the new one is welcomed.
  void connect(std::int64_t now_ns) noexcept;
  [[nodiscard]] State state() const noexcept { return static_cast<State>(state_.load(std::memory_order_acquire)); }
  /// The WELCOME of the live (or last) session.
  [[nodiscard]] const WelcomePayload& welcome() const noexcept { return welcome_; }
  /// When the current attempt last said HELLO.
  [[nodiscard]] std::int64_t lastHello_ns() const noexcept { return last_hello_ns_; }

 private:
  void onHandshake(const Packet& packet, const Received& rx, std::int64_t now_ns) noexcept override;
  [[nodiscard]] bool isHandshake(PacketType type) const noexcept override;
  void afterDrain(std::int64_t now_ns, bool went_silent) noexcept override;
  void onBye() noexcept override { setState(State::kClosed); }
  void onEnded() noexcept override { setState(State::kIdle); }
  void sayHello(std::int64_t now_ns) noexcept;
  void setState(State state) noexcept { state_.store(static_cast<int>(state), std::memory_order_release); }

  bool attempting_ = false;
  Nonce nonce_{};
  Cookie cookie_{};
  std::int64_t last_hello_ns_ = 0;
  WelcomePayload welcome_{};
  std::atomic<int> state_{static_cast<int>(State::kIdle)};
};

/// The end that answers: the device server (data in: COMMAND) and the mentoring leader (PEER).
/// One session at a time; another initiator is answered BUSY while it is live.
class ResponderLinkSession final : public LinkSession {
 public:
  /// `offer`: what each WELCOME says besides the nonce (rate, timeouts, capabilities, limits).
  /// Throws hattr::Error if libsodium cannot start.
  ResponderLinkSession(const AuthKey& shared, PacketType data_in, DatagramLink& link, const WelcomePayload& offer,
                       const LinkSessionTiming& timing);

 private:
  struct Remembered {
    Nonce nonce{};
    std::int64_t opened_ns = 0;
    bool used = false;
  };

  void onHandshake(const Packet& packet, const Received& rx, std::int64_t now_ns) noexcept override;
  [[nodiscard]] bool isHandshake(PacketType type) const noexcept override { return type == PacketType::kHello; }
  void afterDrain(std::int64_t /*now_ns*/, bool /*went_silent*/) noexcept override {}
  [[nodiscard]] Cookie cookieFor(const UdpEndpoint& from, const Nonce& nonce, std::int64_t epoch) const noexcept;
  [[nodiscard]] bool cookieValid(const HelloPayload& hello, const UdpEndpoint& from, std::int64_t now_ns) const noexcept;
  [[nodiscard]] bool remembered(const Nonce& nonce, std::int64_t now_ns) const noexcept;
  [[nodiscard]] bool roomToRemember(std::int64_t now_ns) const noexcept;
  void refuse(const Nonce& nonce, const UdpEndpoint& to, std::int64_t now_ns) noexcept;
  void sendWelcome(std::int64_t now_ns) noexcept;

  WelcomePayload offer_;
  AuthKey cookie_secret_;
  Nonce nonce_{};  // the live session's HELLO nonce
  std::array<Remembered, kNonceMemory> nonces_{};
  std::size_t next_slot_ = 0;
};

}  // namespace hattr::wire
