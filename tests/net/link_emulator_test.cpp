// The link emulator: delay, jitter, loss, reordering and duplication, seeded and exact.

#include <cmath>
#include <thread>

#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/net/link_emulator.hpp"
#include "support/no_allocation.hpp"

namespace hattr::net {
namespace {

constexpr std::int64_t kMs = 1'000'000;

/// Sends `n` one-byte datagrams (their index mod 256), one per millisecond, and collects the
/// arrival time of each delivery by polling every 0.1 ms.
struct Trace {
  std::vector<std::pair<std::int64_t, int>> arrivals;  // (time, index)
  LinkStats stats;
};
Trace run(const LinkConditions& conditions, int n) {
  LinkEmulator link(conditions);
  Trace trace;
  wire::PacketBuffer buffer{};
  for (std::int64_t t = 0; t < (n + 1000) * kMs; t += kMs / 10) {
    if (t % kMs == 0 && t / kMs < n) {
      const std::uint8_t byte = static_cast<std::uint8_t>(t / kMs);
      link.send(std::span(&byte, 1), t);
    }
    std::size_t size = 0;
    while (link.receive(t, buffer, size)) trace.arrivals.emplace_back(t, buffer[0]);
  }
  trace.stats = link.stats();
  return trace;
}

TEST(LinkEmulator, DelaysEveryDatagramByExactlyTheDelayWithoutJitter) {
  const Trace trace = run({.delay_s = 0.05}, 100);
  ASSERT_EQ(trace.arrivals.size(), 100u);
  for (std::size_t i = 0; i < trace.arrivals.size(); ++i) {
    EXPECT_EQ(trace.arrivals[i].first, static_cast<std::int64_t>(i) * kMs + 50 * kMs);
    EXPECT_EQ(trace.arrivals[i].second, static_cast<int>(i));
  }
  EXPECT_EQ(trace.stats.reordered, 0u);
}

TEST(LinkEmulator, LosesAboutTheGivenFractionAndTheSameOnesForTheSameSeed) {
  const LinkConditions c{.loss = 0.05, .seed = 7};
  const Trace a = run(c, 4000);
  const Trace b = run(c, 4000);
  EXPECT_EQ(a.arrivals, b.arrivals);
  const double lost = static_cast<double>(a.stats.lost) / 4000.0;
  EXPECT_NEAR(lost, 0.05, 0.012);  // ±3.5 standard deviations of a binomial(4000, 0.05) fraction
  EXPECT_EQ(a.stats.delivered + a.stats.lost, 4000u);
  const Trace other = run({.loss = 0.05, .seed = 8}, 4000);
  EXPECT_NE(other.arrivals, a.arrivals);
}

TEST(LinkEmulator, JitterWiderThanTheSpacingReordersAndIsCounted) {
  const Trace trace = run({.delay_s = 0.01, .jitter_s = 0.005, .seed = 3}, 250);  // indices fit a byte
  ASSERT_EQ(trace.arrivals.size(), 250u);
  std::uint64_t inversions = 0;
  int newest = -1;
  for (const auto& [t, index] : trace.arrivals) {
    if (index < newest) ++inversions;
    newest = std::max(newest, index);
  }
  EXPECT_GT(inversions, 25u);
  EXPECT_EQ(trace.stats.reordered, inversions);
  for (const auto& [t, index] : trace.arrivals) {
    EXPECT_GE(t, index * kMs + 10 * kMs);
    EXPECT_LE(t, index * kMs + 15 * kMs + kMs / 10);
  }
}

TEST(LinkEmulator, DuplicatesArriveTwiceAndHeldBackOnesArriveLate) {
  const Trace dup = run({.duplicate = 0.1, .seed = 5}, 1000);
  EXPECT_EQ(dup.arrivals.size(), 1000u + dup.stats.duplicated);
  EXPECT_NEAR(static_cast<double>(dup.stats.duplicated), 100.0, 40.0);
  const Trace held = run({.reorder = 0.1, .reorder_extra_s = 0.003, .seed = 5}, 1000);
  EXPECT_GT(held.stats.reordered, 50u);
}

TEST(LinkEmulator, SendAndReceiveNeverAllocate) {
  LinkEmulator link({.delay_s = 0.01, .jitter_s = 0.002, .loss = 0.1, .duplicate = 0.1});
  wire::PacketBuffer buffer{};
  const test::NoAllocationScope scope;
  for (std::int64_t t = 0; t < 2000 * kMs; t += kMs) {
    link.send(std::span(buffer.data(), 100), t);
    std::size_t size = 0;
    while (link.receive(t, buffer, size)) {
    }
  }
  EXPECT_EQ(scope.allocations(), 0u);
}

TEST(LinkEmulator, RefusesImpossibleConditionsNamingTheField) {
  try {
    LinkEmulator link({.loss = 1.5});
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "link conditions: loss: expected a probability in [0, 1], got 1.5");
  }
}

TEST(LinkRelay, CarriesDatagramsBothWaysOverLoopbackWithTheEmulatedDelay) {
  // An echo "server" on loopback behind a relay with 20 ms each way.
  auto server = wire::UdpSocket::bound(wire::parseUdpEndpoint("127.0.0.1:0", "test", 0));
  LinkRelay relay("127.0.0.1:0", server.localEndpoint().text(), {.delay_s = 0.02}, {.delay_s = 0.02});
  auto client = wire::UdpSocket::connected(relay.endpoint());
  const std::uint8_t ping[3] = {1, 2, 3};
  const std::int64_t sent = wire::monotonicNs();
  ASSERT_TRUE(client.send(ping));
  wire::PacketBuffer buffer{};
  wire::Received got;
  ASSERT_TRUE(server.waitReadable(1'000 * kMs));
  ASSERT_EQ(server.receive(buffer, got), wire::ReceiveStatus::kPacket);
  ASSERT_TRUE(server.sendTo(std::span(buffer.data(), got.size), got.from));
  ASSERT_TRUE(client.waitReadable(1'000 * kMs));
  ASSERT_EQ(client.receive(buffer, got), wire::ReceiveStatus::kPacket);
  const double rtt_ms = static_cast<double>(wire::monotonicNs() - sent) / 1e6;
  EXPECT_EQ(got.size, 3u);
  EXPECT_EQ(buffer[2], 3);
  EXPECT_GE(rtt_ms, 40.0);
  EXPECT_LT(rtt_ms, 200.0);
  relay.stop();
  EXPECT_EQ(relay.forwardStats().delivered, 1u);
  EXPECT_EQ(relay.backStats().delivered, 1u);
}

}  // namespace
}  // namespace hattr::net
