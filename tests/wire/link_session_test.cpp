// The wire protocol's sessions against an attacker on the network, on an in-memory link and a
// simulated clock (nothing here depends on the host's timing): the handshake with its cookie,
// recorded HELLOs replayed (also after a restart and after more sessions than the responder
// remembers nonces of), packets reflected to their sender, a sequence number far ahead, and
// answers no larger than what asked for them. A key holder's own packets stand in for the
// recorded ones.

#include "hattr/wire/link_session.hpp"

#include <deque>
#include <vector>

#include <gtest/gtest.h>

namespace hattr::wire {
namespace {

constexpr std::int64_t kMs = 1'000'000;

/// Two ends in one process. Each datagram an end sends is queued for the other and kept in
/// its record (what an attacker on the path sees); the test can also put any datagram in
/// front of an end, from any address.
class MemoryNetwork {
 public:
  struct Datagram {
    std::vector<std::uint8_t> bytes;
    UdpEndpoint from;
  };

  class End final : public DatagramLink {
   public:
    End(MemoryNetwork& network, int index) : network_(network), index_(index) {}
    bool receive(std::int64_t now_ns, PacketBuffer& buffer, Received& out) noexcept override {
      auto& inbox = network_.inbox_[index_];
      if (inbox.empty()) return false;
      const Datagram& d = inbox.front();
      out.size = d.bytes.size();
      out.from = d.from;
      out.arrival_ns = now_ns;
      std::copy_n(d.bytes.begin(), std::min(d.bytes.size(), buffer.size()), buffer.begin());
      inbox.pop_front();
      return true;
    }
    bool send(std::int64_t /*now_ns*/, std::span<const std::uint8_t> datagram, const UdpEndpoint& to) noexcept override {
      network_.sent_[index_].push_back({{datagram.begin(), datagram.end()}, to});
      if (to == address(1 - index_)) network_.inbox_[1 - index_].push_back({{datagram.begin(), datagram.end()}, address(index_)});
      return true;
    }

   private:
    MemoryNetwork& network_;
    int index_;
  };

  static UdpEndpoint address(int index) { return {.address = 0x0A000001u + static_cast<std::uint32_t>(index), .port = 7400}; }
  End& end(int index) { return index == 0 ? end0_ : end1_; }
  /// Puts a datagram in front of end `index`, as if sent from `from`.
  void inject(int index, const std::vector<std::uint8_t>& bytes, const UdpEndpoint& from) {
    inbox_[index].push_back({bytes, from});
  }
  /// Everything end `index` has sent so far (to anyone).
  [[nodiscard]] const std::vector<Datagram>& sent(int index) const { return sent_[index]; }

 private:
  std::deque<Datagram> inbox_[2];
  std::vector<Datagram> sent_[2];
  End end0_{*this, 0};
  End end1_{*this, 1};
};

/// Index 0 responds (as a mentoring leader), index 1 initiates; PEER packets both ways.
struct Pair {
  AuthKey key = randomKey();
  MemoryNetwork network;
  std::unique_ptr<ResponderLinkSession> responder =
      std::make_unique<ResponderLinkSession>(key, PacketType::kPeer, network.end(0), WelcomePayload{.rate_hz = 1.0,
                                                                                                .session_timeout_ns = 500 * kMs,
                                                                                                .command_timeout_ns = 10 * kMs},
                                         LinkSessionTiming{});
  InitiatorLinkSession initiator{key, PacketType::kPeer, network.end(1), MemoryNetwork::address(0), LinkSessionTiming{}};
  std::int64_t now = 1'000 * kMs;

  /// One tick of both ends, 1 ms apart; each sends a PEER when it has a session.
  void tick(bool initiator_sends = true, bool responder_sends = true) {
    now += kMs;
    responder->pump(now);
    initiator.pump(now);
    if (initiator_sends && initiator.live()) (void)initiator.send(PeerPayload{.t_s = 1e-9 * static_cast<double>(now)}, now);
    if (responder_sends && responder->confirmed()) (void)responder->send(PeerPayload{.t_s = 1e-9 * static_cast<double>(now)}, now);
  }
  void ticks(int n) {
    for (int i = 0; i < n; ++i) tick();
  }
  /// The initiator's HELLO that opened its newest session (the one with a cookie).
  std::vector<std::uint8_t> openingHello() const {
    const auto& sent = network.sent(1);
    for (auto it = sent.rbegin(); it != sent.rend(); ++it) {
      PacketHeader header;
      DropReason why{};
      if (readHeader(it->bytes, header, why) && header.type == PacketType::kHello) return it->bytes;
    }
    return {};
  }
  std::uint64_t responderDrops(DropReason reason) const { return responder->stats().drops[static_cast<std::size_t>(reason)]; }
};

TEST(WireSession, TheHandshakeTakesACookieAndTheResponderStreamsOnlyAfterTheInitiatorsFirstData) {
  Pair p;
  p.initiator.connect(p.now);
  p.tick(false, true);  // HELLO → COOKIE → HELLO → WELCOME: the initiator is live, the responder waits
  p.tick(false, true);
  ASSERT_EQ(p.initiator.state(), InitiatorLinkSession::State::kLive);
  EXPECT_TRUE(p.responder->live());
  EXPECT_FALSE(p.responder->confirmed());
  EXPECT_EQ(p.responder->stats().cookies, 1u);
  EXPECT_EQ(p.initiator.stats().cookies, 1u);
  p.ticks(5);
  EXPECT_TRUE(p.responder->confirmed());
  EXPECT_GE(p.responder->stats().data_received, 4u);
  EXPECT_GE(p.initiator.stats().data_received, 3u);
  EXPECT_EQ(p.responder->stats().sessions, 1u);
}

// Issue 40, item 1: recorded HELLOs, replayed alternately at 2 a second for a minute while a
// real initiator asks, never open a session nor hold the responder: the nonces of recent
// sessions are remembered for the cookie's life, and afterwards the cookie is stale. Also
// after more than kNonceMemory sessions, and after the responder restarted.
TEST(WireSession, RecordedHellosOpenNothingAfterRestartsAndMoreSessionsThanTheResponderRemembers) {
  Pair p;
  std::vector<std::vector<std::uint8_t>> recorded;
  for (int n = 0; n < static_cast<int>(kNonceMemory) + 36; ++n) {  // 100 sessions, 0.1 s apart
    p.initiator.connect(p.now);
    p.ticks(3);
    ASSERT_EQ(p.initiator.state(), InitiatorLinkSession::State::kLive) << "session " << n;
    recorded.push_back(p.openingHello());
    p.initiator.close(p.now);
    p.now += 100 * kMs;
  }
  const std::uint64_t sessions = p.responder->stats().sessions;
  ASSERT_EQ(sessions, recorded.size());

  // The last one replayed at once: remembered. Then two a second for a minute, while the real
  // initiator connects after 30 s and must be served.
  p.network.inject(0, recorded.back(), MemoryNetwork::address(1));
  p.tick(false, false);
  EXPECT_EQ(p.responderDrops(DropReason::kReplayed), 1u);
  bool real_connected = false;
  for (int half_second = 0; half_second < 120; ++half_second) {
    const auto& a = recorded[static_cast<std::size_t>(half_second) % recorded.size()];
    const auto& b = recorded[static_cast<std::size_t>(half_second + 1) % recorded.size()];
    p.network.inject(0, half_second % 2 == 0 ? a : b, MemoryNetwork::address(1));
    if (half_second == 60) p.initiator.connect(p.now);
    p.ticks(5);
    real_connected = real_connected || p.initiator.state() == InitiatorLinkSession::State::kLive;
    p.now += 495 * kMs;
    if (half_second == 60) {
      EXPECT_TRUE(p.responder->live());
      EXPECT_EQ(p.initiator.state(), InitiatorLinkSession::State::kLive);
      p.initiator.close(p.now);
    }
  }
  EXPECT_TRUE(real_connected);
  EXPECT_EQ(p.responder->stats().sessions, sessions + 1) << "a replayed HELLO opened a session";
  EXPECT_EQ(p.responder->stats().busy, 0u) << "a replay held the responder so a real initiator was refused";

  // A restarted responder (a new cookie secret) answers every recorded HELLO with a COOKIE only.
  p.responder = std::make_unique<ResponderLinkSession>(p.key, PacketType::kPeer, p.network.end(0), WelcomePayload{.rate_hz = 1.0,
                                                                                                              .session_timeout_ns = 1,
                                                                                                              .command_timeout_ns = 1},
                                                   LinkSessionTiming{});
  for (std::size_t i = 0; i < 8; ++i) {
    p.network.inject(0, recorded[i], MemoryNetwork::address(1));
    p.now += kMs;
    p.responder->pump(p.now);
  }
  EXPECT_EQ(p.responder->stats().sessions, 0u);
  EXPECT_EQ(p.responder->stats().cookies, 8u);
}

// Issue 40, item 2: a packet reflected back to its sender unchanged by a relay without the key
// is not taken as the other side's: it fails the MAC of the other direction's key, and the real
// partner's packets keep arriving. Both directions.
TEST(WireSession, APacketReflectedToItsSenderIsDroppedAndTheSessionGoesOn) {
  Pair p;
  p.initiator.connect(p.now);
  p.ticks(10);
  ASSERT_TRUE(p.responder->confirmed());
  const auto last = [&](int index) { return p.network.sent(index).back().bytes; };
  const std::uint64_t initiator_before = p.initiator.stats().data_received;
  const std::uint64_t responder_before = p.responder->stats().data_received;
  p.network.inject(1, last(1), MemoryNetwork::address(0));  // the initiator's own PEER, as if from the responder
  p.network.inject(0, last(0), MemoryNetwork::address(1));  // and the responder's
  p.ticks(10);
  EXPECT_EQ(p.initiator.stats().drops[static_cast<std::size_t>(DropReason::kBadMac)], 1u);
  EXPECT_EQ(p.responderDrops(DropReason::kBadMac), 1u);
  EXPECT_EQ(p.initiator.stats().data_received, initiator_before + 10);
  EXPECT_EQ(p.responder->stats().data_received, responder_before + 10);
  EXPECT_EQ(p.initiator.stats().drops[static_cast<std::size_t>(DropReason::kOutOfOrder)], 0u);
  EXPECT_TRUE(p.initiator.live());
}

// Issue 40, item 6: one authentic sequence number of 2^64 - 1 (a key holder's) is refused as
// beyond the window; the real sender's next packets are taken.
TEST(WireSession, ASequenceNumberFarAheadIsRefusedAndTheRealSenderGoesOn) {
  Pair p;
  p.initiator.connect(p.now);
  p.ticks(5);
  ASSERT_TRUE(p.responder->confirmed());
  // The initiator's own key forges the jump: header.sequence = 2^64 - 1 in its session.
  const auto& mine = p.network.sent(1).back().bytes;
  PacketHeader header;
  DropReason why{};
  ASSERT_TRUE(readHeader(mine, header, why));
  const DirectionKeys keys = directionKeys(p.key, Role::kInitiator);
  PacketBuffer buffer{};
  const std::size_t size = encodePacket(
      {{.session_id = header.session_id, .sequence = ~std::uint64_t{0}, .sender_time_ns = p.now}, PeerPayload{}}, keys.send,
      buffer);
  p.network.inject(0, {buffer.begin(), buffer.begin() + static_cast<std::ptrdiff_t>(size)}, MemoryNetwork::address(1));
  const std::uint64_t before = p.responder->stats().data_received;
  p.ticks(5);
  EXPECT_EQ(p.responderDrops(DropReason::kBadValue), 1u);
  EXPECT_EQ(p.responder->stats().data_received, before + 5);
}

// Issue 40, item 6: every answer a responder gives a HELLO (COOKIE, WELCOME, BUSY) is at most
// as large as the HELLO; retries of an unconfirmed session's HELLO are answered, repeats of a
// confirmed one are replays.
TEST(WireSession, NoAnswerIsLargerThanTheHelloThatAskedForIt) {
  Pair p;
  p.initiator.connect(p.now);
  p.tick(false, false);
  p.tick(false, false);
  ASSERT_TRUE(p.responder->live());
  const auto opening = p.openingHello();
  p.network.inject(0, opening, MemoryNetwork::address(1));  // a retry: WELCOME again
  p.tick(false, false);
  p.ticks(3);
  p.network.inject(0, opening, MemoryNetwork::address(1));  // now a replay
  MemoryNetwork::Datagram stranger{opening, {.address = 0x0A0000FFu, .port = 9}};
  p.network.inject(0, stranger.bytes, stranger.from);  // from elsewhere: its own COOKIE
  p.tick(false, false);
  std::size_t answers = 0;
  for (const auto& d : p.network.sent(0)) {
    PacketHeader h;
    DropReason why{};
    ASSERT_TRUE(readHeader(d.bytes, h, why));
    if (h.type == PacketType::kPeer) continue;
    ++answers;
    EXPECT_LE(d.bytes.size(), opening.size()) << "type " << static_cast<int>(h.type);
  }
  EXPECT_EQ(answers, 4u);  // COOKIE, WELCOME, WELCOME again, the stranger's COOKIE
  EXPECT_EQ(p.responderDrops(DropReason::kReplayed), 1u);
  EXPECT_EQ(p.responder->stats().sessions, 1u);
}

// A flood of handshake packets costs a pump at most kMaxHandshakesPerPump MAC checks.
TEST(WireSession, AFloodOfHandshakesIsVerifiedOnlyAFewAPump) {
  Pair p;
  // The drain budget is real time: on a slow host (ThreadSanitizer, clean-clone run 20) it cut
  // this pump short after 94 datagrams. The rate limit is what is tested: a budget no host reaches.
  p.responder = std::make_unique<ResponderLinkSession>(
      p.key, PacketType::kPeer, p.network.end(0),
      WelcomePayload{.rate_hz = 1.0, .session_timeout_ns = 500 * kMs, .command_timeout_ns = 10 * kMs},
      LinkSessionTiming{.drain_budget_ns = 60'000'000'000});
  p.initiator.connect(p.now);
  p.ticks(5);
  PacketBuffer buffer{};
  const std::size_t size = encodePacket({{}, HelloPayload{}}, randomKey(), buffer);
  for (int i = 0; i < 100; ++i) {
    p.network.inject(0, {buffer.begin(), buffer.begin() + static_cast<std::ptrdiff_t>(size)}, MemoryNetwork::address(1));
  }
  const std::uint64_t before = p.responder->stats().data_received;
  p.tick();
  EXPECT_EQ(p.responderDrops(DropReason::kBadMac), static_cast<std::uint64_t>(kMaxHandshakesPerPump));
  EXPECT_EQ(p.responderDrops(DropReason::kRateLimited), 100u - kMaxHandshakesPerPump);
  EXPECT_EQ(p.responder->stats().data_received, before + 1);
}

}  // namespace
}  // namespace hattr::wire
