#include "hattr/wire/packet.hpp"

#include <sodium.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <ctime>

namespace hattr::wire {
namespace {

// Sizes of each packet type: header + payload + MAC (docs/protocol.md has the layouts).
// A HELLO is padded to the size of the largest answer (WELCOME): no answer is ever larger
// than the packet that asked for it, so the responder cannot amplify a spoofed flood.
constexpr std::size_t kWelcomeSize = kHeaderSize + 152 + kMacSize;           // 216
constexpr std::size_t kHelloSize = kWelcomeSize;                             // 216
constexpr std::size_t kCookiePacketSize = kHeaderSize + kNonceSize + kCookieSize + kMacSize;  // 96
constexpr std::size_t kBusySize = kHeaderSize + kNonceSize + kMacSize;       // 80
constexpr std::size_t kStateSize = kHeaderSize + 168 + kMacSize;             // 232
constexpr std::size_t kCommandSize = kHeaderSize + 104 + kMacSize;           // 168
constexpr std::size_t kByeSize = kHeaderSize + 8 + kMacSize;                 // 72
constexpr std::size_t kPeerSize = kHeaderSize + 144 + kMacSize;              // 208
static_assert(kStateSize == kMaxPacketSize);
static_assert(crypto_auth_BYTES == kMacSize && crypto_auth_KEYBYTES == kKeySize);
static_assert(kHelloSize >= kCookiePacketSize && kHelloSize >= kBusySize);

// Pen-state flags (STATE) and command flags (COMMAND).
constexpr std::uint32_t kPenHasForce = 1u << 0;
constexpr std::uint32_t kPenHasPressure = 1u << 1;
constexpr std::uint32_t kPenHasTilt = 1u << 2;
constexpr std::uint32_t kCommandHasHand = 1u << 0;
constexpr std::uint32_t kCommandPenDown = 1u << 1;
// Capability flags (WELCOME).
constexpr std::uint32_t kCapForceSensor = 1u << 0;
constexpr std::uint32_t kCapPressure = 1u << 1;
constexpr std::uint32_t kCapTilt = 1u << 2;

/// Little-endian writer over a packet buffer; the layout is explicit, never a struct's.
class Writer {
 public:
  explicit Writer(std::uint8_t* data) noexcept : data_(data) {}
  void u16(std::uint16_t v) noexcept { raw(v, 2); }
  void u32(std::uint32_t v) noexcept { raw(v, 4); }
  void u64(std::uint64_t v) noexcept { raw(v, 8); }
  void i64(std::int64_t v) noexcept { raw(static_cast<std::uint64_t>(v), 8); }
  void f64(double v) noexcept { raw(std::bit_cast<std::uint64_t>(v), 8); }
  void vec3(const Vec3& v) noexcept { f64(v.x()); f64(v.y()); f64(v.z()); }
  void bytes(const std::uint8_t* p, std::size_t n) noexcept { std::memcpy(data_ + at_, p, n); at_ += n; }
  [[nodiscard]] std::size_t at() const noexcept { return at_; }

 private:
  void raw(std::uint64_t v, int n) noexcept {
    for (int i = 0; i < n; ++i) data_[at_++] = static_cast<std::uint8_t>(v >> (8 * i));
  }
  std::uint8_t* data_;
  std::size_t at_ = 0;
};

/// Little-endian reader; reports a non-finite double through `finite`.
class Reader {
 public:
  explicit Reader(const std::uint8_t* data, std::size_t at = 0) noexcept : data_(data), at_(at) {}
  std::uint16_t u16() noexcept { return static_cast<std::uint16_t>(raw(2)); }
  std::uint32_t u32() noexcept { return static_cast<std::uint32_t>(raw(4)); }
  std::uint64_t u64() noexcept { return raw(8); }
  std::int64_t i64() noexcept { return static_cast<std::int64_t>(raw(8)); }
  double f64() noexcept {
    const double v = std::bit_cast<double>(raw(8));
    finite_ = finite_ && std::isfinite(v);
    return v;
  }
  Vec3 vec3() noexcept {
    const double x = f64();
    const double y = f64();
    const double z = f64();
    return {x, y, z};
  }
  void bytes(std::uint8_t* p, std::size_t n) noexcept { std::memcpy(p, data_ + at_, n); at_ += n; }
  [[nodiscard]] bool finite() const noexcept { return finite_; }

 private:
  std::uint64_t raw(int n) noexcept {
    std::uint64_t v = 0;
    for (int i = 0; i < n; ++i) v |= static_cast<std::uint64_t>(data_[at_++]) << (8 * i);
    return v;
  }
  const std::uint8_t* data_;
  std::size_t at_;
  bool finite_ = true;
};

PacketType typeOf(const Payload& payload) noexcept {
  constexpr PacketType kTypes[] = {PacketType::kHello, PacketType::kWelcome, PacketType::kBusy,
                                   PacketType::kState, PacketType::kCommand, PacketType::kBye,
                                   PacketType::kPeer,  PacketType::kCookie};
  return kTypes[payload.index()];
}

std::uint32_t statusCode(DeviceStatus s) noexcept {
  return s == DeviceStatus::kOk ? 0u : s == DeviceStatus::kFault ? 1u : 2u;
}

// Payload writers, one per type, in the order of docs/protocol.md.
// HELLO and COOKIE share their layout: a nonce, a cookie.
template <typename P>
void writeNonceAndCookie(Writer& w, const P& p) noexcept {
  w.bytes(p.nonce.data(), kNonceSize);
  w.bytes(p.cookie.data(), kCookieSize);
}
template <typename P>
P readNonceAndCookie(Reader& r) noexcept {
  P p;
  r.bytes(p.nonce.data(), kNonceSize);
  r.bytes(p.cookie.data(), kCookieSize);
  return p;
}
void writePayload(Writer& w, const HelloPayload& p) noexcept { writeNonceAndCookie(w, p); }
void writePayload(Writer& w, const CookiePayload& p) noexcept { writeNonceAndCookie(w, p); }
void writePayload(Writer& w, const BusyPayload& p) noexcept { w.bytes(p.nonce.data(), kNonceSize); }
void writePayload(Writer& w, const ByePayload& p) noexcept {
  w.u32(p.reason);
  w.u32(0);
}
void writePayload(Writer& w, const WelcomePayload& p) noexcept {
  w.bytes(p.nonce.data(), kNonceSize);
  w.f64(p.rate_hz);
  w.i64(p.session_timeout_ns);
  w.i64(p.command_timeout_ns);
  w.u32((p.capabilities.force_sensor ? kCapForceSensor : 0u) | (p.capabilities.pressure ? kCapPressure : 0u) |
        (p.capabilities.tilt ? kCapTilt : 0u));
  w.u32(static_cast<std::uint32_t>(p.limits.degrees_of_freedom));
  w.vec3(p.limits.workspace_min_m);
  w.vec3(p.limits.workspace_max_m);
  w.f64(p.limits.peak_force_N);
  w.f64(p.limits.continuous_force_N);
  w.f64(p.limits.max_stiffness_N_per_m);
  w.f64(p.limits.max_damping_N_s_per_m);
  w.f64(p.limits.nominal_rate_hz);
  w.f64(p.limits.mass_kg);
  w.f64(p.limits.damping_N_s_per_m);
}
void writePayload(Writer& w, const StatePayload& p) noexcept {
  w.f64(p.pen.t_s);
  w.vec3(p.pen.p_WT);
  w.vec3(p.pen.v_WT);
  w.vec3(p.pen.f_measured_W);
  w.f64(p.pen.pressure_raw);
  w.f64(p.pen.azimuth_rad);
  w.f64(p.pen.altitude_rad);
  w.vec3(p.f_applied_W);
  w.i64(p.echo_sender_time_ns);
  w.i64(p.hold_ns);
  w.u64(p.echo_sequence);
  w.u32(p.pen.buttons);
  w.u32((p.pen.has_force ? kPenHasForce : 0u) | (p.pen.has_pressure ? kPenHasPressure : 0u) |
        (p.pen.has_tilt ? kPenHasTilt : 0u));
  w.u32(statusCode(p.device_status));
  w.u32(p.server_flags);
}
void writePayload(Writer& w, const CommandPayload& p) noexcept {
  w.vec3(p.f_on_pen_W);
  w.vec3(p.hand.p_target_W);
  w.vec3(p.hand.v_target_W);
  w.f64(p.hand.press_N);
  w.f64(p.hand.azimuth_rad);
  w.f64(p.hand.altitude_rad);
  w.u32((p.has_hand ? kCommandHasHand : 0u) | (p.hand.pen_down ? kCommandPenDown : 0u));
  w.u32(0);
}

void writePayload(Writer& w, const PeerPayload& p) noexcept {
  w.f64(p.t_s);
  w.vec3(p.p_WT);
  w.vec3(p.v_WT);
  w.vec3(p.f_user_W);
  w.vec3(p.f_coupling_W);
  w.f64(p.energy_in_J);
  w.f64(p.energy_out_J);
  w.i64(p.echo_sender_time_ns);
  w.i64(p.hold_ns);
  w.u32(p.coupling);
  w.u32(p.flags);
}

bool inRange(std::int64_t v, std::int64_t lo, std::int64_t hi) noexcept { return v >= lo && v <= hi; }

/// A WELCOME: the rate, timeouts, capabilities and the device's limits.
bool readWelcome(Reader& r, Payload& out) noexcept {
  WelcomePayload p;
  r.bytes(p.nonce.data(), kNonceSize);
  p.rate_hz = r.f64();
  p.session_timeout_ns = r.i64();
  p.command_timeout_ns = r.i64();
  const std::uint32_t caps = r.u32();
  p.capabilities = {.force_sensor = (caps & kCapForceSensor) != 0, .pressure = (caps & kCapPressure) != 0,
                    .tilt = (caps & kCapTilt) != 0};
  const std::uint32_t dof = r.u32();
  p.limits.degrees_of_freedom = static_cast<int>(dof);
  p.limits.workspace_min_m = r.vec3();
  p.limits.workspace_max_m = r.vec3();
  p.limits.peak_force_N = r.f64();
  p.limits.continuous_force_N = r.f64();
  p.limits.max_stiffness_N_per_m = r.f64();
  p.limits.max_damping_N_s_per_m = r.f64();
  p.limits.nominal_rate_hz = r.f64();
  p.limits.mass_kg = r.f64();
  p.limits.damping_N_s_per_m = r.f64();
  out = p;
  return dof >= 1 && dof <= 6 && p.rate_hz > 0.0 && p.session_timeout_ns > 0 &&
         p.session_timeout_ns <= kMaxTimeoutNs && p.command_timeout_ns > 0 && p.command_timeout_ns <= kMaxTimeoutNs;
}

/// A STATE: the pen, the force applied, echo and hold times, status.
bool readState(Reader& r, Payload& out) noexcept {
  StatePayload p;
  p.pen.t_s = r.f64();
  p.pen.p_WT = r.vec3();
  p.pen.v_WT = r.vec3();
  p.pen.f_measured_W = r.vec3();
  p.pen.pressure_raw = r.f64();
  p.pen.azimuth_rad = r.f64();
  p.pen.altitude_rad = r.f64();
  p.f_applied_W = r.vec3();
  p.echo_sender_time_ns = r.i64();
  p.hold_ns = r.i64();
  p.echo_sequence = r.u64();
  p.pen.buttons = r.u32();
  const std::uint32_t flags = r.u32();
  p.pen.has_force = (flags & kPenHasForce) != 0;
  p.pen.has_pressure = (flags & kPenHasPressure) != 0;
  p.pen.has_tilt = (flags & kPenHasTilt) != 0;
  const std::uint32_t status = r.u32();
  p.device_status = status == 0 ? DeviceStatus::kOk : status == 1 ? DeviceStatus::kFault : DeviceStatus::kDisconnected;
  p.server_flags = r.u32();
  out = p;
  return status <= 2 && inRange(p.hold_ns, 0, kMaxHoldNs) && p.echo_sender_time_ns >= 0;
}

/// A PEER: the other station's pen, coupling force and energy.
bool readPeer(Reader& r, Payload& out) noexcept {
  PeerPayload p;
  p.t_s = r.f64();
  p.p_WT = r.vec3();
  p.v_WT = r.vec3();
  p.f_user_W = r.vec3();
  p.f_coupling_W = r.vec3();
  p.energy_in_J = r.f64();
  p.energy_out_J = r.f64();
  p.echo_sender_time_ns = r.i64();
  p.hold_ns = r.i64();
  p.coupling = r.u32();
  p.flags = r.u32();
  out = p;
  return p.energy_in_J >= 0.0 && p.energy_out_J >= 0.0 && inRange(p.hold_ns, 0, kMaxHoldNs) &&
         p.echo_sender_time_ns >= 0 && p.coupling <= 3;
}

/// A COMMAND: the force on the pen, and the simulated hand's.
bool readCommand(Reader& r, Payload& out) noexcept {
  CommandPayload p;
  p.f_on_pen_W = r.vec3();
  p.hand.p_target_W = r.vec3();
  p.hand.v_target_W = r.vec3();
  p.hand.press_N = r.f64();
  p.hand.azimuth_rad = r.f64();
  p.hand.altitude_rad = r.f64();
  const std::uint32_t flags = r.u32();
  p.has_hand = (flags & kCommandHasHand) != 0;
  p.hand.pen_down = (flags & kCommandPenDown) != 0;
  out = p;
  return true;
}

// Payload readers; false for a value out of range (non-finite numbers are checked by the caller).
bool readPayload(Reader& r, PacketType type, Payload& out) noexcept {
  switch (type) {
    case PacketType::kHello: out = readNonceAndCookie<HelloPayload>(r); return true;
    case PacketType::kCookie: out = readNonceAndCookie<CookiePayload>(r); return true;
    case PacketType::kBusy: {
      BusyPayload p;
      r.bytes(p.nonce.data(), kNonceSize);
      out = p;
      return true;
    }
    case PacketType::kBye: {
      ByePayload p;
      p.reason = r.u32();
      out = p;
      return true;
    }
    case PacketType::kWelcome: return readWelcome(r, out);
    case PacketType::kState: return readState(r, out);
    case PacketType::kPeer: return readPeer(r, out);
    case PacketType::kCommand: return readCommand(r, out);
  }
  return false;
}

}  // namespace

std::size_t packetSize(PacketType type) noexcept {
  switch (type) {
    case PacketType::kHello: return kHelloSize;
    case PacketType::kWelcome: return kWelcomeSize;
    case PacketType::kBusy: return kBusySize;
    case PacketType::kState: return kStateSize;
    case PacketType::kCommand: return kCommandSize;
    case PacketType::kBye: return kByeSize;
    case PacketType::kPeer: return kPeerSize;
    case PacketType::kCookie: return kCookiePacketSize;
  }
  return 0;
}

std::string_view dropReasonName(DropReason reason) noexcept {
  switch (reason) {
    case DropReason::kBadSize: return "bad_size";
    case DropReason::kBadHeader: return "bad_header";
    case DropReason::kUnknownType: return "unknown_type";
    case DropReason::kBadMac: return "bad_mac";
    case DropReason::kBadValue: return "bad_value";
    case DropReason::kWrongSession: return "wrong_session";
    case DropReason::kReplayed: return "replayed";
    case DropReason::kOutOfOrder: return "out_of_order";
    case DropReason::kUnexpected: return "unexpected";
    case DropReason::kBusy: return "busy";
    case DropReason::kBadVersion: return "bad_version";
    case DropReason::kRateLimited: return "rate_limited";
    case DropReason::kCount: break;
  }
  return "unknown";
}

std::size_t encodePacket(const Packet& packet, const AuthKey& key, PacketBuffer& out) noexcept {
  const PacketType type = typeOf(packet.payload);
  Writer w(out.data());
  w.bytes(kMagic.data(), kMagic.size());
  w.u16(kProtocolVersion);
  w.u16(static_cast<std::uint16_t>(type));
  w.u64(packet.header.session_id);
  w.u64(packet.header.sequence);
  w.i64(packet.header.sender_time_ns);
  std::visit([&w](const auto& p) { writePayload(w, p); }, packet.payload);
  const std::size_t size = packetSize(type);
  // Zero the reserved bytes (if any) up to the tag, then authenticate everything before it.
  std::memset(out.data() + w.at(), 0, size - kMacSize - w.at());
  crypto_auth(out.data() + size - kMacSize, out.data(), size - kMacSize, key.bytes().data());
  return size;
}

bool verifyMac(std::span<const std::uint8_t> datagram, const AuthKey& key) noexcept {
  if (datagram.size() < kHeaderSize + kMacSize) return false;
  const std::size_t body = datagram.size() - kMacSize;
  return crypto_auth_verify(datagram.data() + body, datagram.data(), body, key.bytes().data()) == 0;
}

bool readHeader(std::span<const std::uint8_t> datagram, PacketHeader& out, DropReason& why) noexcept {
  if (datagram.size() < kHeaderSize + kMacSize || datagram.size() > kMaxPacketSize) {
    why = DropReason::kBadSize;
    return false;
  }
  if (std::memcmp(datagram.data(), kMagic.data(), kMagic.size()) != 0) {
    why = DropReason::kBadHeader;
    return false;
  }
  Reader header(datagram.data(), kMagic.size());
  if (header.u16() != kProtocolVersion) {
    why = DropReason::kBadVersion;
    return false;
  }
  const auto type = static_cast<PacketType>(header.u16());
  const std::size_t size = packetSize(type);
  if (size == 0) {
    why = DropReason::kUnknownType;
    return false;
  }
  if (datagram.size() != size) {
    why = DropReason::kBadSize;
    return false;
  }
  out.type = type;
  out.session_id = header.u64();
  out.sequence = header.u64();
  out.sender_time_ns = header.i64();
  return true;
}

bool decodePacket(std::span<const std::uint8_t> datagram, const AuthKey& key, Packet& out, DropReason& why) noexcept {
  if (!readHeader(datagram, out.header, why)) return false;
  // Authentication before any further field is used.
  if (!verifyMac(datagram, key)) {
    why = DropReason::kBadMac;
    return false;
  }
  Reader payload(datagram.data(), kHeaderSize);
  if (!readPayload(payload, out.header.type, out.payload) || !payload.finite() || out.header.sender_time_ns < 0) {
    why = DropReason::kBadValue;
    return false;
  }
  return true;
}

bool SequenceCheck::accept(std::uint64_t sequence, DropReason& why) noexcept {
  // Checked arithmetic: newest_ < sequence here, so the difference cannot wrap.
  if (sequence > newest_ && sequence - newest_ > kSequenceWindow) {
    why = DropReason::kBadValue;
    return false;
  }
  if (sequence > newest_) {
    if (newest_ != 0) lost_ += sequence - newest_ - 1;
    newest_ = sequence;
    return true;
  }
  why = sequence == newest_ ? DropReason::kReplayed : DropReason::kOutOfOrder;
  return false;
}

DropCounts dropsSince(const DropCounts& now, const DropCounts& before) noexcept {
  DropCounts out{};
  for (std::size_t i = 0; i < kDropReasonCount; ++i) out[i] = now[i] - before[i];
  return out;
}

DropCounts DropCounters::snapshot() const noexcept {
  DropCounts out{};
  for (std::size_t i = 0; i < kDropReasonCount; ++i) out[i] = counts_[i].load(std::memory_order_relaxed);
  return out;
}

std::uint64_t DropCounters::total() const noexcept {
  std::uint64_t sum = 0;
  for (const auto& c : counts_) sum += c.load(std::memory_order_relaxed);
  return sum;
}

RandomStream::RandomStream() {
  initCrypto();
  randombytes_buf(seed_.data(), seed_.size());
}

void RandomStream::fill(std::span<std::uint8_t> out) noexcept {
  // A fresh 12-byte nonce per call keeps every output independent.
  std::array<std::uint8_t, crypto_stream_chacha20_ietf_NONCEBYTES> nonce{};
  ++counter_;
  for (int i = 0; i < 8; ++i) nonce[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(counter_ >> (8 * i));
  crypto_stream_chacha20_ietf(out.data(), out.size(), nonce.data(), seed_.data());
}

std::uint64_t RandomStream::nextNonZero() noexcept {
  std::array<std::uint8_t, 8> bytes{};
  std::uint64_t value = 0;
  while (value == 0) {
    fill(bytes);
    std::memcpy(&value, bytes.data(), sizeof value);
  }
  return value;
}

std::int64_t monotonicNs() noexcept {
  timespec ts{};
  ::clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

}  // namespace hattr::wire
