#pragma once
/// The hattr wire protocol, version 2: fixed-size, little-endian UDP packets authenticated with
/// HMAC-SHA-512-256 (libsodium crypto_auth) under a key per direction. One protocol for the
/// network device (udp://, `hattr device serve`) and live mentoring between two stations. The
/// byte layout, the handshake, the threat model and the timeouts: docs/protocol.md.
///
/// Packets are hostile until proven otherwise: sizes are fixed per type, lengths are never
/// trusted, the MAC is verified before any field beyond the fixed header is used, numbers are
/// range-checked, and every dropped packet is counted by reason. Units: SI; times are
/// nanoseconds of the sender's clock (CLOCK_MONOTONIC, or a station's loop time).
///
/// Threads: everything here is noexcept and runs on the servo thread (no allocation, no
/// locks, no blocking), except RandomStream's constructor (setup).

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <variant>

#include "hattr/core/device_limits.hpp"
#include "hattr/core/hand_command.hpp"
#include "hattr/core/pen_state.hpp"
#include "hattr/wire/keys.hpp"

namespace hattr::wire {

inline constexpr std::array<std::uint8_t, 4> kMagic = {'H', 'A', 'T', 'R'};
inline constexpr std::uint16_t kProtocolVersion = 2;
inline constexpr std::size_t kHeaderSize = 32;  ///< magic, version, type, session, sequence, sender time
inline constexpr std::size_t kMacSize = 32;     ///< crypto_auth tag (HMAC-SHA-512-256)
inline constexpr std::size_t kNonceSize = 16;   ///< the initiator's nonce in HELLO / COOKIE / WELCOME / BUSY
inline constexpr std::size_t kCookieSize = 16;  ///< the responder's stateless cookie (COOKIE, HELLO)
inline constexpr std::size_t kMaxPacketSize = 232;
/// An authentic sequence number more than this ahead of the newest accepted is refused: one
/// packet can never push a direction's window out of reach (2^16 packets: 65 s at 1 kHz,
/// far beyond any session timeout).
inline constexpr std::uint64_t kSequenceWindow = std::uint64_t{1} << 16;
/// Hold fields (STATE, PEER) above this are refused as out of range [ns].
inline constexpr std::int64_t kMaxHoldNs = 1'000'000'000;
/// Timeouts a WELCOME may announce at most [ns] (one hour).
inline constexpr std::int64_t kMaxTimeoutNs = 3'600'000'000'000;

enum class PacketType : std::uint16_t {
  kHello = 1,    ///< initiator → responder: open a session (nonce, and the cookie once it has one)
  kWelcome = 2,  ///< responder → initiator: the session id, the device's limits, capabilities, rate
  kBusy = 3,     ///< responder → initiator: refused, another peer is being served
  kState = 4,    ///< device server → client: the pen
  kCommand = 5,  ///< client → device server: the force on the pen, optionally a simulated hand
  kBye = 6,      ///< either way: the session ends
  kPeer = 7,     ///< station ↔ station (live mentoring): a pen, its person's force, the coupling's energy
  kCookie = 8,   ///< responder → initiator: say HELLO again with this cookie (proves the address, bounds replays)
};

/// The fixed size of a packet of this type [bytes] (0 for an unknown type).
[[nodiscard]] std::size_t packetSize(PacketType type) noexcept;

/// Why a datagram was dropped. Every drop is counted under exactly one reason.
enum class DropReason : std::uint8_t {
  kBadSize,       ///< size differs from its type's fixed size (or no header at all)
  kBadHeader,     ///< wrong magic
  kUnknownType,   ///< packet type not in this protocol version
  kBadMac,        ///< the tag does not verify: tampered, another key, or this side's own packet reflected
  kBadValue,      ///< authentic, but a number is not finite, a field out of range, or a sequence jump beyond the window
  kWrongSession,  ///< not of the live session (or from another address)
  kReplayed,      ///< sequence number (or hello nonce) already seen: duplicate or replay
  kOutOfOrder,    ///< older than a packet already accepted: late
  kUnexpected,    ///< authentic, but not a type this side accepts now
  kBusy,          ///< a HELLO refused with BUSY: another peer is being served
  kBadVersion,    ///< magic right, another protocol version (an older or newer hattr)
  kRateLimited,   ///< a handshake packet beyond the few one pump verifies (a flood): dropped unverified
  kCount,
};
inline constexpr std::size_t kDropReasonCount = static_cast<std::size_t>(DropReason::kCount);
/// snake_case name for JSON and messages ("bad_mac").
[[nodiscard]] std::string_view dropReasonName(DropReason reason) noexcept;

/// Drops by reason (index: DropReason), a snapshot of plain numbers: the one counters type
/// every statistics struct that counts drops carries (wire::LinkSessionStats, net::MentorStats,
/// net::DeviceServerStats, device::LinkStats), each reason documented above, written to JSON
/// by ops::dropsJson with every reason, zeros included.
using DropCounts = std::array<std::uint64_t, kDropReasonCount>;
/// Each reason's count of `now` minus that of `before` (taken first).
[[nodiscard]] DropCounts dropsSince(const DropCounts& now, const DropCounts& before) noexcept;

using Nonce = std::array<std::uint8_t, kNonceSize>;
using Cookie = std::array<std::uint8_t, kCookieSize>;

/// The fixed header every packet starts with.
struct PacketHeader {
  PacketType type = PacketType::kHello;
  std::uint64_t session_id = 0;   ///< chosen by the responder in WELCOME; 0 before
  std::uint64_t sequence = 0;     ///< per session and direction, strictly increasing; 0 outside a session
  std::int64_t sender_time_ns = 0;
};

struct HelloPayload {
  Nonce nonce{};
  Cookie cookie{};  ///< all zero on the first HELLO of an attempt; then the responder's COOKIE
};

struct CookiePayload {
  Nonce nonce{};    ///< echo of the HELLO's nonce
  Cookie cookie{};
};

struct WelcomePayload {
  Nonce nonce{};                         ///< echo of the HELLO's nonce
  double rate_hz = 0.0;                  ///< the responder's servo rate
  std::int64_t session_timeout_ns = 0;   ///< the responder ends a silent session after this
  std::int64_t command_timeout_ns = 0;   ///< the device server zeroes the force without a COMMAND for this
  DeviceCapabilities capabilities;
  DeviceLimits limits;
};

struct BusyPayload {
  Nonce nonce{};
};

/// Flags in StatePayload::server_flags.
inline constexpr std::uint32_t kServerNoCommand = 1u << 0;    ///< no live COMMAND: zero force applied
inline constexpr std::uint32_t kServerSafetyFault = 1u << 1;  ///< the server's safety path has a latched fault

struct StatePayload {
  PenState pen;                            ///< the pen at the sender's tick (t_s: the sender's loop time)
  Vec3 f_applied_W = Vec3::Zero();         ///< force written to the device at the previous tick [N]
  std::int64_t echo_sender_time_ns = 0;    ///< sender time of the newest COMMAND received (0: none)
  std::int64_t hold_ns = 0;                ///< from that COMMAND's arrival to this STATE's sending
  std::uint64_t echo_sequence = 0;         ///< its sequence number (0: none)
  DeviceStatus device_status = DeviceStatus::kOk;  ///< the sender's device
  std::uint32_t server_flags = 0;
};

struct CommandPayload {
  Vec3 f_on_pen_W = Vec3::Zero();  ///< force on the pen [N, W]
  bool has_hand = false;           ///< `hand` drives a simulated pen on the server (ignored by hardware)
  HandCommand hand;
};

/// Live mentoring (docs/mentoring.md): what one station tells the other once per tick.
struct PeerPayload {
  double t_s = 0.0;                        ///< the sender's loop time [s]
  Vec3 p_WT = Vec3::Zero();                ///< its pen tip [m, W]
  Vec3 v_WT = Vec3::Zero();                ///< [m/s]
  Vec3 f_user_W = Vec3::Zero();            ///< the force its person exerts on the paper [N]
  Vec3 f_coupling_W = Vec3::Zero();        ///< the coupling force it applied to its pen [N]
  double energy_in_J = 0.0;                ///< energy that entered the coupling at its port so far [J] (≥ 0, non-decreasing)
  double energy_out_J = 0.0;               ///< energy the coupling gave its person so far [J] (≥ 0)
  std::int64_t echo_sender_time_ns = 0;    ///< sender time of the newest PEER received (0: none)
  std::int64_t hold_ns = 0;                ///< from its arrival to this packet's sending
  std::uint32_t coupling = 0;              ///< the coupling the sender runs (net::Coupling as a number)
  std::uint32_t flags = 0;                 ///< kPeerPenDown, kPeerLinkUp
};
inline constexpr std::uint32_t kPeerPenDown = 1u << 0;  ///< its pen touches the paper
inline constexpr std::uint32_t kPeerLinkUp = 1u << 1;   ///< it hears the other station

struct ByePayload {
  std::uint32_t reason = 0;  ///< 0: normal close
};

using Payload = std::variant<HelloPayload, WelcomePayload, BusyPayload, StatePayload, CommandPayload, ByePayload,
                             PeerPayload, CookiePayload>;

struct Packet {
  PacketHeader header;  ///< header.type is set from the payload when encoding
  Payload payload;
};

using PacketBuffer = std::array<std::uint8_t, kMaxPacketSize>;

/// Encodes a packet (header, payload, MAC under `key`, the sender's direction key) into
/// `out`; returns its size.
std::size_t encodePacket(const Packet& packet, const AuthKey& key, PacketBuffer& out) noexcept;

/// The fixed header only (no MAC): size against the type's fixed size, magic, version, type.
/// Cheap: for filtering before the MAC. False with `why` on the first failure.
[[nodiscard]] bool readHeader(std::span<const std::uint8_t> datagram, PacketHeader& out, DropReason& why) noexcept;

/// Checks and decodes a datagram: readHeader, then the MAC under `key` (the other side's
/// direction key), and only then the payload (non-finite numbers and fields out of range →
/// kBadValue). On success fills `out` and returns true; otherwise sets `why` and leaves `out`
/// unspecified. Session and sequence checks are the session's (wire/link_session.hpp).
[[nodiscard]] bool decodePacket(std::span<const std::uint8_t> datagram, const AuthKey& key, Packet& out,
                                DropReason& why) noexcept;

/// True if the last kMacSize bytes of `datagram` are the tag of the bytes before them.
[[nodiscard]] bool verifyMac(std::span<const std::uint8_t> datagram, const AuthKey& key) noexcept;

/// Strictly increasing sequence numbers of one direction of one session, within a window.
class SequenceCheck {
 public:
  /// True if `sequence` is newer than every accepted one and at most kSequenceWindow ahead
  /// (then accepted; a gap counts as lost). False with `why` = kReplayed (equal to the
  /// newest), kOutOfOrder (older) or kBadValue (beyond the window).
  [[nodiscard]] bool accept(std::uint64_t sequence, DropReason& why) noexcept;
  void reset() noexcept { newest_ = 0; lost_ = 0; }
  [[nodiscard]] std::uint64_t newest() const noexcept { return newest_; }
  [[nodiscard]] std::uint64_t lost() const noexcept { return lost_; }

 private:
  std::uint64_t newest_ = 0;
  std::uint64_t lost_ = 0;
};

/// Drops by reason, written by the servo thread, read by any thread.
class DropCounters {
 public:
  void count(DropReason reason) noexcept {
    counts_[static_cast<std::size_t>(reason)].fetch_add(1, std::memory_order_relaxed);
  }
  [[nodiscard]] std::uint64_t operator[](DropReason reason) const noexcept {
    return counts_[static_cast<std::size_t>(reason)].load(std::memory_order_relaxed);
  }
  [[nodiscard]] std::uint64_t total() const noexcept;
  /// A snapshot, indexed by DropReason.
  [[nodiscard]] DropCounts snapshot() const noexcept;

 private:
  std::array<std::atomic<std::uint64_t>, kDropReasonCount> counts_{};
};

/// Unpredictable bytes without a system call (ChaCha20 keyed once from the system's
/// randomness), for session ids, nonces and cookie secrets chosen on the servo thread.
class RandomStream {
 public:
  /// Seeds from libsodium's randombytes. Setup only.
  RandomStream();
  void fill(std::span<std::uint8_t> out) noexcept;
  [[nodiscard]] std::uint64_t nextNonZero() noexcept;

 private:
  std::array<std::uint8_t, 32> seed_{};
  std::uint64_t counter_ = 0;
};

/// CLOCK_MONOTONIC now [ns] (the clock of every sender time of the network device).
[[nodiscard]] std::int64_t monotonicNs() noexcept;

}  // namespace hattr::wire
