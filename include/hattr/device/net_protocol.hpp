#pragma once
/// The hattr network protocol: fixed-size, little-endian UDP packets authenticated with
/// HMAC-SHA-512-256 (libsodium crypto_auth). One protocol for the network device (udp://,
/// `hattr device serve`) and, later, live mentoring between two stations: a peer sends
/// STATE packets (a pen) and COMMAND packets (a force, optionally a simulated hand's
/// command). The byte layout, the handshake and the timeouts: docs/protocol.md.
///
/// Packets are hostile until proven otherwise: sizes are fixed per type, lengths are never
/// trusted, the MAC is verified before any field beyond the fixed header is used, and every
/// dropped packet is counted by reason. Units: SI; times are nanoseconds of the sender's
/// CLOCK_MONOTONIC.
///
/// Threads: everything marked noexcept here runs on the servo thread (no allocation, no
/// locks, no blocking); key-file functions are setup code and throw hattr::InputError.

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string_view>
#include <variant>

#include "hattr/device/device.hpp"
#include "hattr/device/hand.hpp"

namespace hattr::device::net {

inline constexpr std::array<std::uint8_t, 4> kMagic = {'H', 'A', 'T', 'R'};
inline constexpr std::uint16_t kProtocolVersion = 1;
inline constexpr std::size_t kHeaderSize = 32;  ///< magic, version, type, session, sequence, sender time
inline constexpr std::size_t kMacSize = 32;     ///< crypto_auth tag (HMAC-SHA-512-256)
inline constexpr std::size_t kKeySize = 32;     ///< crypto_auth key
inline constexpr std::size_t kNonceSize = 16;   ///< client nonce in HELLO / WELCOME / BUSY
inline constexpr std::size_t kMaxPacketSize = 232;

enum class PacketType : std::uint16_t {
  kHello = 1,    ///< client → server: open a session (client nonce)
  kWelcome = 2,  ///< server → client: the session id, the device's limits, capabilities, rate
  kBusy = 3,     ///< server → client: refused, another client is being served
  kState = 4,    ///< server → client (or station → station): the pen
  kCommand = 5,  ///< client → server: the force on the pen, optionally a simulated hand
  kBye = 6,      ///< either way: the session ends
  kPeer = 7,     ///< station ↔ station (live mentoring): a pen, its person's force, the coupling's energy
};

/// The fixed size of a packet of this type [bytes] (0 for an unknown type).
[[nodiscard]] std::size_t packetSize(PacketType type) noexcept;

/// Why a datagram was dropped. Every drop is counted under exactly one reason.
enum class DropReason : std::uint8_t {
  kBadSize,       ///< size differs from its type's fixed size (or no header at all)
  kBadHeader,     ///< wrong magic or protocol version
  kUnknownType,   ///< packet type not in this protocol version
  kBadMac,        ///< the tag does not verify: tampered, or another key
  kBadValue,      ///< authentic, but a number is not finite or a field out of range
  kWrongSession,  ///< authentic, but not of the live session (or from another address)
  kReplayed,      ///< sequence number (or hello nonce) already seen: duplicate or replay
  kOutOfOrder,    ///< older than a packet already accepted: late
  kUnexpected,    ///< authentic, but not a type this side accepts now
  kBusy,          ///< a HELLO refused with BUSY: another client is being served
  kCount,
};
inline constexpr std::size_t kDropReasonCount = static_cast<std::size_t>(DropReason::kCount);
/// snake_case name for JSON and messages ("bad_mac").
[[nodiscard]] std::string_view dropReasonName(DropReason reason) noexcept;

using Nonce = std::array<std::uint8_t, kNonceSize>;

/// The fixed header every packet starts with.
struct PacketHeader {
  PacketType type = PacketType::kHello;
  std::uint64_t session_id = 0;   ///< chosen by the server in WELCOME; 0 before
  std::uint64_t sequence = 0;     ///< per session and direction, strictly increasing
  std::int64_t sender_time_ns = 0;
};

struct HelloPayload {
  Nonce client_nonce{};
};

struct WelcomePayload {
  Nonce client_nonce{};                  ///< echo of the HELLO's nonce
  double rate_hz = 0.0;                  ///< the server's servo rate
  std::int64_t session_timeout_ns = 0;   ///< the server ends a silent session after this
  std::int64_t command_timeout_ns = 0;   ///< the server zeroes the force without a COMMAND for this
  DeviceCapabilities capabilities;
  DeviceLimits limits;
};

struct BusyPayload {
  Nonce client_nonce{};
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

using Payload =
    std::variant<HelloPayload, WelcomePayload, BusyPayload, StatePayload, CommandPayload, ByePayload, PeerPayload>;

struct Packet {
  PacketHeader header;  ///< header.type is set from the payload when encoding
  Payload payload;
};

using PacketBuffer = std::array<std::uint8_t, kMaxPacketSize>;

/// A 32-byte authentication key. Never printed; wiped on destruction.
class AuthKey {
 public:
  AuthKey() = default;
  explicit AuthKey(const std::array<std::uint8_t, kKeySize>& bytes) noexcept : bytes_(bytes) {}
  AuthKey(const AuthKey&) = default;
  AuthKey& operator=(const AuthKey&) = default;
  ~AuthKey();
  [[nodiscard]] const std::array<std::uint8_t, kKeySize>& bytes() const noexcept { return bytes_; }

 private:
  std::array<std::uint8_t, kKeySize> bytes_{};
};

/// Reads a key file: exactly 64 hexadecimal characters, optionally followed by one newline.
/// Throws InputError naming the file and what was expected and found (never key material).
[[nodiscard]] AuthKey readKeyFile(const std::filesystem::path& file);
/// A fresh random key (libsodium randombytes).
[[nodiscard]] AuthKey randomKey();
/// Writes `key` as 64 hex characters and a newline, file mode 0600. Refuses to replace an
/// existing file unless `overwrite` (InputError); other I/O failures throw hattr::Error.
void writeKeyFile(const std::filesystem::path& file, const AuthKey& key, bool overwrite);

/// Encodes a packet (header, payload, MAC) into `out`; returns its size. Servo-thread safe.
std::size_t encodePacket(const Packet& packet, const AuthKey& key, PacketBuffer& out) noexcept;

/// Checks and decodes a datagram: size against the type's fixed size, magic and version,
/// then the MAC, and only then the payload (non-finite numbers → kBadValue). On success
/// fills `out` and returns true; otherwise sets `why` and leaves `out` unspecified.
/// Session and sequence checks are the caller's (SequenceCheck). Servo-thread safe.
[[nodiscard]] bool decodePacket(std::span<const std::uint8_t> datagram, const AuthKey& key, Packet& out,
                                DropReason& why) noexcept;

/// True if the last kMacSize bytes of `datagram` are the tag of the bytes before them.
[[nodiscard]] bool verifyMac(std::span<const std::uint8_t> datagram, const AuthKey& key) noexcept;

/// Strictly increasing sequence numbers of one direction of one session.
class SequenceCheck {
 public:
  /// True if `sequence` is newer than every accepted one (then accepted; a gap counts as
  /// lost). False with `why` = kReplayed (equal to the newest) or kOutOfOrder (older).
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

 private:
  std::array<std::atomic<std::uint64_t>, kDropReasonCount> counts_{};
};

/// Unpredictable bytes without a system call (ChaCha20 keyed once from the system's
/// randomness), for session ids and nonces chosen on the servo thread.
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

/// CLOCK_MONOTONIC now [ns] (the clock of every sender time).
[[nodiscard]] std::int64_t monotonicNs() noexcept;

/// Makes sure libsodium is initialised (idempotent, thread-safe). Throws hattr::Error if not.
void initCrypto();

}  // namespace hattr::device::net
