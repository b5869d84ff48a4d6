#include "hattr/wire/link_session.hpp"

#include <sodium.h>

#include <algorithm>
#include <cstring>

namespace hattr::wire {
namespace {

constexpr std::size_t kMaxPerPump = 4096;     // datagrams read by one pump at most
constexpr std::size_t kBudgetCheckEvery = 8;  // datagrams between looks at the clock

// Cookie input: the initiator's address and port, its nonce, the epoch.
constexpr std::size_t kCookieInputSize = 4 + 2 + kNonceSize + 8;

}  // namespace

// ---- LinkSession: what both ends share ------------------------------------------------------

LinkSession::LinkSession(const AuthKey& shared, Role role, PacketType data_in, DatagramLink& link,
                         const LinkSessionTiming& timing)
    : keys_(directionKeys(shared, role)), link_(link), timing_(timing), data_in_(data_in) {}

// Everything waiting, within the budget; then the session's timeout.
void LinkSession::pump(std::int64_t now_ns) noexcept {
  const std::int64_t started = monotonicNs();
  handshakes_this_pump_ = 0;
  Received rx;
  for (std::size_t n = 0; n < kMaxPerPump; ++n) {
    if (n % kBudgetCheckEvery == kBudgetCheckEvery - 1 && monotonicNs() - started > timing_.drain_budget_ns) break;
    if (!link_.receive(now_ns, rx_buffer_, rx)) break;
    receive(rx, now_ns);
  }
  const bool went_silent = live_ && now_ns - last_heard_ns_ > timing_.session_timeout_ns;
  if (went_silent) {
    end();
    bump(timeouts_);
  }
  afterDrain(now_ns, went_silent);
}

// The checks, cheapest first: size and header, the type this end takes, then (for a session
// packet) its session and sender before the MAC, the MAC and the values, the sequence.
void LinkSession::receive(const Received& rx, std::int64_t now_ns) noexcept {
  if (rx.size > rx_buffer_.size()) {
    drops_.count(DropReason::kBadSize);
    return;
  }
  const std::span<const std::uint8_t> datagram(rx_buffer_.data(), rx.size);
  PacketHeader header;
  DropReason why{};
  if (!readHeader(datagram, header, why)) {
    drops_.count(why);
    return;
  }
  const bool handshake = isHandshake(header.type);
  if (!handshake && header.type != data_in_ && header.type != PacketType::kBye) {
    drops_.count(DropReason::kUnexpected);
    return;
  }
  if (!handshake && (!live_ || header.session_id != id_ || rx.from != peer_)) {
    drops_.count(DropReason::kWrongSession);
    return;
  }
  if (handshake && ++handshakes_this_pump_ > kMaxHandshakesPerPump) {
    drops_.count(DropReason::kRateLimited);
    return;
  }
  Packet packet;
  if (!decodePacket(datagram, keys_.receive, packet, why)) {
    drops_.count(why);
    return;
  }
  if (handshake) {
    onHandshake(packet, rx, now_ns);
    return;
  }
  if (!received_.accept(header.sequence, why)) {
    drops_.count(why);
    return;
  }
  data_lost_.store(lost_before_ + received_.lost(), std::memory_order_relaxed);
  last_heard_ns_ = rx.arrival_ns;
  if (header.type == PacketType::kBye) {
    end();
    bump(byes_);
    onBye();
    return;
  }
  newest_ = packet;
  newest_arrival_ns_ = rx.arrival_ns;
  fresh_ = true;
  confirmed_ = true;
  bump(data_received_);
}

bool LinkSession::takeData(Packet& out, std::int64_t& arrival_ns) noexcept {
  if (!fresh_) return false;
  fresh_ = false;
  out = newest_;
  arrival_ns = newest_arrival_ns_;
  return true;
}

bool LinkSession::send(const Payload& payload, std::int64_t now_ns) noexcept {
  if (!live_) return false;
  sendPacket({{.session_id = id_, .sequence = nextSequence(), .sender_time_ns = now_ns}, payload}, peer_, now_ns);
  return true;
}

void LinkSession::close(std::int64_t now_ns) noexcept {
  if (!live_) return;
  (void)send(ByePayload{}, now_ns);
  end();
}

void LinkSession::open(std::uint64_t id, const UdpEndpoint& peer, std::int64_t now_ns) noexcept {
  id_ = id;
  peer_ = peer;
  lost_before_ += received_.lost();
  received_.reset();
  send_sequence_ = 0;
  last_heard_ns_ = now_ns;
  confirmed_ = false;
  fresh_ = false;
  live_ = true;
  live_flag_.store(true, std::memory_order_release);
  sessions_.fetch_add(1, std::memory_order_acq_rel);
}

void LinkSession::end() noexcept {
  live_ = false;
  confirmed_ = false;
  fresh_ = false;
  live_flag_.store(false, std::memory_order_release);
  onEnded();
}

void LinkSession::sendPacket(const Packet& packet, const UdpEndpoint& to, std::int64_t now_ns) noexcept {
  const std::size_t size = encodePacket(packet, keys_.send, tx_buffer_);
  (void)link_.send(now_ns, std::span(tx_buffer_.data(), size), to);
}

LinkSessionStats LinkSession::stats() const noexcept {
  LinkSessionStats s;
  s.sessions = sessions_.load(std::memory_order_relaxed);
  s.timeouts = timeouts_.load(std::memory_order_relaxed);
  s.byes_received = byes_.load(std::memory_order_relaxed);
  s.busy = busy_.load(std::memory_order_relaxed);
  s.cookies = cookies_.load(std::memory_order_relaxed);
  s.data_received = data_received_.load(std::memory_order_relaxed);
  s.data_lost = data_lost_.load(std::memory_order_relaxed);
  s.drops = drops_.snapshot();
  return s;
}

// ---- InitiatorLinkSession -------------------------------------------------------------------

InitiatorLinkSession::InitiatorLinkSession(const AuthKey& shared, PacketType data_in, DatagramLink& link,
                                           const UdpEndpoint& responder, const LinkSessionTiming& timing)
    : LinkSession(shared, Role::kInitiator, data_in, link, timing) {
  peer_ = responder;
}

void InitiatorLinkSession::connect(std::int64_t now_ns) noexcept {
  random_.fill(nonce_);
  cookie_.fill(0);
  attempting_ = true;
  if (!live_) setState(State::kConnecting);
  sayHello(now_ns);
}

void InitiatorLinkSession::sayHello(std::int64_t now_ns) noexcept {
  last_hello_ns_ = now_ns;
  sendPacket({{.session_id = 0, .sequence = 0, .sender_time_ns = now_ns}, HelloPayload{nonce_, cookie_}}, peer_, now_ns);
}

void InitiatorLinkSession::afterDrain(std::int64_t now_ns, bool went_silent) noexcept {
  if (went_silent) setState(State::kSilent);
  // An attempt under way says HELLO again until it is answered.
  if (attempting_ && now_ns - last_hello_ns_ >= timing_.hello_retry_ns) sayHello(now_ns);
}

bool InitiatorLinkSession::isHandshake(PacketType type) const noexcept {
  return type == PacketType::kWelcome || type == PacketType::kCookie || type == PacketType::kBusy;
}

// Answers to the attempt under way only: its nonce, from the responder.
void InitiatorLinkSession::onHandshake(const Packet& packet, const Received& rx, std::int64_t now_ns) noexcept {
  const auto nonceOf = [](const Payload& p) -> const Nonce& {
    if (const auto* w = std::get_if<WelcomePayload>(&p)) return w->nonce;
    if (const auto* c = std::get_if<CookiePayload>(&p)) return c->nonce;
    return std::get<BusyPayload>(p).nonce;
  };
  if (!attempting_ || rx.from != peer_ || sodium_memcmp(nonceOf(packet.payload).data(), nonce_.data(), kNonceSize) != 0) {
    drops_.count(DropReason::kUnexpected);
    return;
  }
  switch (packet.header.type) {
    case PacketType::kCookie:
      // The responder asks for its cookie: say HELLO again at once, with it.
      cookie_ = std::get<CookiePayload>(packet.payload).cookie;
      bump(cookies_);
      sayHello(now_ns);
      return;
    case PacketType::kBusy:
      attempting_ = false;
      bump(busy_);
      if (!live_) setState(State::kRefused);
      return;
    case PacketType::kWelcome: {
      if (packet.header.session_id == 0) {
        drops_.count(DropReason::kBadValue);
        return;
      }
      attempting_ = false;
      welcome_ = std::get<WelcomePayload>(packet.payload);
      open(packet.header.session_id, peer_, rx.arrival_ns);
      DropReason why{};
      (void)received_.accept(packet.header.sequence, why);  // the WELCOME is the responder's first packet
      setState(State::kLive);
      return;
    }
    default: drops_.count(DropReason::kUnexpected); return;
  }
}

// ---- ResponderLinkSession -------------------------------------------------------------------

ResponderLinkSession::ResponderLinkSession(const AuthKey& shared, PacketType data_in, DatagramLink& link,
                                           const WelcomePayload& offer, const LinkSessionTiming& timing)
    : LinkSession(shared, Role::kResponder, data_in, link, timing), offer_(offer) {
  std::array<std::uint8_t, kKeySize> secret{};
  random_.fill(secret);
  cookie_secret_ = AuthKey(secret);
  sodium_memzero(secret.data(), secret.size());
}

// The cookie: a MAC of the initiator's address, its nonce and the epoch under a secret only
// this responder knows (new at every start), cut to 16 bytes. Nothing is stored.
Cookie ResponderLinkSession::cookieFor(const UdpEndpoint& from, const Nonce& nonce, std::int64_t epoch) const noexcept {
  std::array<std::uint8_t, kCookieInputSize> input{};
  for (int i = 0; i < 4; ++i) input[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(from.address >> (8 * i));
  input[4] = static_cast<std::uint8_t>(from.port);
  input[5] = static_cast<std::uint8_t>(from.port >> 8);
  std::memcpy(input.data() + 6, nonce.data(), kNonceSize);
  for (int i = 0; i < 8; ++i) {
    input[6 + kNonceSize + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(static_cast<std::uint64_t>(epoch) >> (8 * i));
  }
  std::array<std::uint8_t, crypto_auth_BYTES> tag{};
  crypto_auth(tag.data(), input.data(), input.size(), cookie_secret_.bytes().data());
  Cookie cookie{};
  std::memcpy(cookie.data(), tag.data(), kCookieSize);
  return cookie;
}

// Good in the epoch it was made and the next.
bool ResponderLinkSession::cookieValid(const HelloPayload& hello, const UdpEndpoint& from, std::int64_t now_ns) const noexcept {
  const std::int64_t epoch = now_ns / kCookieEpochNs;
  for (const std::int64_t e : {epoch, epoch - 1}) {
    const Cookie expected = cookieFor(from, hello.nonce, e);
    if (sodium_memcmp(expected.data(), hello.cookie.data(), kCookieSize) == 0) return true;
  }
  return false;
}

bool ResponderLinkSession::remembered(const Nonce& nonce, std::int64_t now_ns) const noexcept {
  return std::any_of(nonces_.begin(), nonces_.end(), [&](const Remembered& r) {
    return r.used && now_ns - r.opened_ns < 2 * kCookieEpochNs && r.nonce == nonce;
  });
}

bool ResponderLinkSession::roomToRemember(std::int64_t now_ns) const noexcept {
  const Remembered& slot = nonces_[next_slot_];
  return !slot.used || now_ns - slot.opened_ns >= 2 * kCookieEpochNs;
}

void ResponderLinkSession::refuse(const Nonce& nonce, const UdpEndpoint& to, std::int64_t now_ns) noexcept {
  // Counted before the answer: an initiator that has read it sees the count.
  bump(busy_);
  drops_.count(DropReason::kBusy);
  sendPacket({{.session_id = 0, .sequence = 0, .sender_time_ns = now_ns}, BusyPayload{nonce}}, to, now_ns);
}

void ResponderLinkSession::sendWelcome(std::int64_t now_ns) noexcept {
  WelcomePayload welcome = offer_;
  welcome.nonce = nonce_;
  sendPacket({{.session_id = id_, .sequence = nextSequence(), .sender_time_ns = now_ns}, welcome}, peer_, now_ns);
}

// A HELLO without a good cookie gets one (no state kept, no larger answer than the HELLO); a
// retried one of the live, unconfirmed session its WELCOME again; a nonce already used is a
// replay; another initiator while a session is live gets BUSY; otherwise a new session (also
// the same initiator starting over).
void ResponderLinkSession::onHandshake(const Packet& packet, const Received& rx, std::int64_t now_ns) noexcept {
  const auto& hello = std::get<HelloPayload>(packet.payload);
  if (!cookieValid(hello, rx.from, now_ns)) {
    bump(cookies_);
    sendPacket({{.session_id = 0, .sequence = 0, .sender_time_ns = now_ns},
                CookiePayload{hello.nonce, cookieFor(rx.from, hello.nonce, now_ns / kCookieEpochNs)}},
               rx.from, now_ns);
    return;
  }
  if (live_ && rx.from == peer_ && hello.nonce == nonce_) {
    if (confirmed_) {
      drops_.count(DropReason::kReplayed);
    } else {
      sendWelcome(now_ns);
    }
    return;
  }
  if (remembered(hello.nonce, now_ns)) {
    drops_.count(DropReason::kReplayed);
    return;
  }
  if ((live_ && rx.from != peer_) || !roomToRemember(now_ns)) {
    refuse(hello.nonce, rx.from, now_ns);
    return;
  }
  nonces_[next_slot_] = {.nonce = hello.nonce, .opened_ns = now_ns, .used = true};
  next_slot_ = (next_slot_ + 1) % kNonceMemory;
  nonce_ = hello.nonce;
  open(random_.nextNonZero(), rx.from, rx.arrival_ns);
  sendWelcome(now_ns);
}

}  // namespace hattr::wire
