// The device server and the udp:// client in one process, on loopback (127.0.0.1 only).

#include "hattr/net/device_server.hpp"

#include <chrono>
#include <cmath>
#include <limits>
#include <thread>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/device/udp_device.hpp"
#include "hattr/wire/link_session.hpp"
#include "support/host_stalls.hpp"
#include "support/thread_sanitizer.hpp"
#include "support/no_allocation.hpp"
#include "support/test_support.hpp"

namespace hattr::net {
namespace {

using device::DeviceStatus;
using wire::DropReason;
using ::testing::AllOf;
using ::testing::HasSubstr;

using Clock = std::chrono::steady_clock;

/// A key file in a temporary folder, and servers and clients that use it.
struct Rig {
  test::TempDir dir;
  std::filesystem::path key_file = dir / "shared.key";
  Rig() { wire::writeKeyFile(key_file, wire::randomKey(), false); }

  DeviceServerConfig config(std::string device_uri = "sim://pen", std::string listen = "127.0.0.1:0") const {
    DeviceServerConfig c;
    c.device_uri = std::move(device_uri);
    c.listen = std::move(listen);
    c.key = wire::readKeyFile(key_file);
    c.realtime.policy = servo::RealtimePolicy::kSkip;
    return c;
  }
  std::string uri(const DeviceServer& server, const std::string& extra = "") const {
    return "udp://" + server.endpoint().text() + "?key=" + key_file.string() + extra;
  }
  std::unique_ptr<device::UdpDevice> client(const DeviceServer& server, device::HandScript* hand = nullptr,
                                            const std::string& extra = "") const {
    const std::string text = uri(server, extra);
    return std::make_unique<device::UdpDevice>(device::udpDeviceParams(device::parseDeviceUri(text)), text, hand);
  }
};

std::chrono::nanoseconds sinceStart(Clock::time_point start) { return Clock::now() - start; }

/// Polls read()+write() every 0.5 ms until `until` says stop or `limit` passes; returns
/// the time it took and the last status. `largest_gap`, when given, gets the longest time
/// between two polls (the host holding this thread up).
template <typename Until>
std::pair<std::chrono::nanoseconds, DeviceStatus> poll(device::UdpDevice& client, Until until,
                                                       std::chrono::milliseconds limit, Vec3 force = Vec3::Zero(),
                                                       std::chrono::nanoseconds* largest_gap = nullptr) {
  const auto start = Clock::now();
  auto last = start;
  DeviceStatus status = DeviceStatus::kOk;
  PenState pen;
  while (Clock::now() - start < limit) {
    const auto now = Clock::now();
    if (largest_gap != nullptr) *largest_gap = std::max(*largest_gap, std::chrono::nanoseconds(now - last));
    last = now;
    status = client.read(sinceStart(start), pen);
    (void)client.write(force);
    if (until(status)) break;
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
  return {Clock::now() - start, status};
}

TEST(DeviceServer, ClientReadsThePenAndTheServerClampsTheForceToItsDeviceLimits) {
  (void)test::passesUnlessTheHostStalls([&](std::uint64_t& stalls) {
    Rig rig;
    DeviceServer server(rig.config("sim://pen?continuous_force_N=0.5"));
    server.start();
    // The client bridges 20 ms of missing states, longer than the server loop's 10 ms stall
    // threshold: a server thread held up long enough to cut the link is a counted stall.
    // (With the default 5 ms, a 5-10 ms hold-up on a loaded host read as disconnected.)
    auto client = rig.client(server, nullptr, "&hold_ms=20");
    EXPECT_DOUBLE_EQ(client->limits().continuous_force_N, 0.5);
    EXPECT_DOUBLE_EQ(client->serverRate_hz(), 1000.0);
    EXPECT_EQ(client->clocking(), device::DeviceClocking::kHostRealTime);
    EXPECT_TRUE(client->capabilities().tilt);

    // 50 N asked for, beyond any limit: the server's safety path gives at most 0.5 N.
    double largest_applied = 0.0;
    const auto [took, status] = poll(
        *client,
        [&](DeviceStatus) {
          largest_applied = std::max(largest_applied, server.appliedForce().norm());
          return false;
        },
        std::chrono::milliseconds(1000), Vec3(50.0, 0.0, 0.0));
    stalls = server.loop().counters().stalls.load();
    EXPECT_EQ(status, DeviceStatus::kOk);
    EXPECT_DOUBLE_EQ(server.commandedForce().x(), 50.0);
    EXPECT_LE(largest_applied, 0.5 + 1e-12);
    EXPECT_GT(largest_applied, 0.4);  // after the 0.25 s ramp
    PenState pen;
    ASSERT_EQ(client->read(std::chrono::nanoseconds(0), pen), DeviceStatus::kOk);
    EXPECT_GT(pen.p_WT.x(), 0.0);  // pushed along +x
    const DeviceServerStats stats = server.stats();
    EXPECT_EQ(stats.sessions, 1u);
    EXPECT_GT(stats.commands_applied, 100u);
    EXPECT_EQ(stats.drops[static_cast<std::size_t>(DropReason::kBadMac)], 0u);
    EXPECT_GT(client->linkStats().rtt.count(), 100u);
  });
}

TEST(DeviceServer, ASecondClientIsRefusedWithBusyAndAClearMessage) {
  Rig rig;
  DeviceServer server(rig.config());
  server.start();
  auto first = rig.client(server);
  try {
    auto second = rig.client(server);
    ADD_FAILURE() << "a second client was served";
  } catch (const InputError& e) {
    const std::string address = server.endpoint().text();
    EXPECT_THAT(e.what(), HasSubstr("udp://" + address + ": the device server at " + address +
                                    " already serves another client"));
  }
  EXPECT_EQ(server.stats().busy_refusals, 1u);
  EXPECT_EQ(server.stats().sessions, 1u);
  // The first client is still served; after its BYE the next one is.
  EXPECT_EQ(poll(*first, [](DeviceStatus) { return true; }, std::chrono::milliseconds(5)).second, DeviceStatus::kOk);
  first.reset();
  auto third = rig.client(server);
  EXPECT_EQ(server.stats().sessions, 2u);
  EXPECT_EQ(server.stats().byes, 1u);
}

TEST(DeviceServer, AWrongKeyLooksLikeNoAnswerAndTheServerCountsABadMac) {
  Rig rig;
  DeviceServer server(rig.config());
  server.start();
  const auto other_key = rig.dir / "other.key";
  wire::writeKeyFile(other_key, wire::randomKey(), false);
  const std::string text = "udp://" + server.endpoint().text() + "?key=" + other_key.string() + "&timeout_s=0.15";
  try {
    (void)device::openDevice(text, nullptr);
    ADD_FAILURE() << "opened with the wrong key";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("udp://" + server.endpoint().text() +
                                          ": no answer from a hattr device server within 0.15 s"),
                                HasSubstr("a wrong key file looks like this")));
  }
  EXPECT_GE(server.stats().drops[static_cast<std::size_t>(DropReason::kBadMac)], 1u);
  EXPECT_EQ(server.stats().sessions, 0u);
}

TEST(DeviceServer, NothingListeningIsReportedAsRefused) {
  Rig rig;
  std::string address;
  {
    DeviceServer gone(rig.config());
    address = gone.endpoint().text();
  }
  try {
    (void)device::openDevice("udp://" + address + "?key=" + rig.key_file.string() + "&timeout_s=0.1", nullptr);
    ADD_FAILURE() << "opened a closed port";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("nothing listens on that port"));
  }
}

/// A hand-made client: the test writes the packets itself (a key holder's packets stand in for
/// recorded ones) and ticks the server by hand.
struct RawClient {
  const Rig& rig;
  DeviceServer& server;
  wire::AuthKey shared = wire::readKeyFile(rig.key_file);
  wire::DirectionKeys keys = wire::directionKeys(shared, wire::Role::kInitiator);
  wire::UdpSocket socket = wire::UdpSocket::connected(server.endpoint());
  std::uint64_t session_id = 0;
  std::chrono::nanoseconds now{0};

  void tick() {
    now += server.loop().period();
    (void)server.loop().tick(now);
  }
  void sendRaw(std::span<const std::uint8_t> bytes) { ASSERT_TRUE(socket.send(bytes)); }
  static std::vector<std::uint8_t> encode(const wire::Packet& packet, const wire::AuthKey& with) {
    wire::PacketBuffer buffer{};
    const std::size_t size = wire::encodePacket(packet, with, buffer);
    return {buffer.begin(), buffer.begin() + static_cast<std::ptrdiff_t>(size)};
  }
  std::vector<std::uint8_t> command(std::uint64_t sequence, Vec3 force, std::uint64_t session) const {
    wire::CommandPayload c;
    c.f_on_pen_W = force;
    return encode({{.session_id = session, .sequence = sequence, .sender_time_ns = wire::monotonicNs()}, c}, keys.send);
  }
  std::vector<std::uint8_t> hello(const wire::Nonce& nonce, const wire::Cookie& cookie = {}) const {
    return encode({{.sender_time_ns = wire::monotonicNs()}, wire::HelloPayload{nonce, cookie}}, keys.send);
  }
  void bye(std::uint64_t sequence) {
    sendRaw(encode({{.session_id = session_id, .sequence = sequence}, wire::ByePayload{}}, keys.send));
    tick();
  }
  /// The next packet the server sent this client (fails the test if none within a tick).
  wire::Packet answer() {
    wire::PacketBuffer buffer{};
    wire::Received rx;
    wire::Packet packet;
    if (!socket.waitReadable(50'000'000) || socket.receive(buffer, rx) != wire::ReceiveStatus::kPacket) {
      ADD_FAILURE() << "no answer from the server";
      return packet;
    }
    wire::DropReason why{};
    EXPECT_TRUE(wire::decodePacket(std::span(buffer.data(), rx.size), keys.receive, packet, why))
        << wire::dropReasonName(why);
    return packet;
  }
  /// HELLO, COOKIE, HELLO with the cookie, WELCOME; returns the HELLO that opened the session.
  std::vector<std::uint8_t> handshake(const wire::Nonce& nonce = {1, 2, 3}) {
    sendRaw(hello(nonce));
    tick();
    const wire::Packet cookie = answer();
    EXPECT_EQ(cookie.header.type, wire::PacketType::kCookie);
    const auto opening = hello(nonce, std::get<wire::CookiePayload>(cookie.payload).cookie);
    sendRaw(opening);
    tick();
    const wire::Packet welcome = answer();
    EXPECT_EQ(welcome.header.type, wire::PacketType::kWelcome);
    session_id = welcome.header.session_id;
    return opening;
  }
};

TEST(DeviceServer, HostilePacketsAreDroppedCountedByReasonAndChangeNothing) {
  Rig rig;
  DeviceServer server(rig.config());
  RawClient client{rig, server};
  const auto opening = client.handshake();
  const Vec3 good(0.3, -0.2, 0.1);
  const auto accepted = client.command(5, good, client.session_id);
  client.sendRaw(accepted);
  client.tick();
  ASSERT_EQ(server.commandedForce(), good);
  const DeviceServerStats before = server.stats();

  // One of each: replayed, late, wrong session, wrong key, wrong size, garbage, bad magic, NaN,
  // a far jump of the sequence, an older protocol version.
  const Vec3 evil(9.0, 9.0, 9.0);
  client.sendRaw(accepted);
  client.sendRaw(client.command(3, evil, client.session_id));
  client.sendRaw(client.command(6, evil, client.session_id + 1));
  wire::CommandPayload c;
  c.f_on_pen_W = evil;
  client.sendRaw(client.encode({{.session_id = client.session_id, .sequence = 7}, c}, wire::randomKey()));
  auto truncated = client.command(8, evil, client.session_id);
  truncated.pop_back();
  client.sendRaw(truncated);
  const std::vector<std::uint8_t> garbage(300, 0x5a);
  client.sendRaw(garbage);
  auto bad_magic = client.command(9, evil, client.session_id);
  bad_magic[0] = 'X';
  client.sendRaw(bad_magic);
  c.f_on_pen_W = Vec3(std::nan(""), 0.0, 0.0);
  client.sendRaw(client.encode({{.session_id = client.session_id, .sequence = 10}, c}, client.keys.send));
  client.sendRaw(client.command(std::numeric_limits<std::uint64_t>::max(), evil, client.session_id));
  auto old_version = client.command(11, evil, client.session_id);
  old_version[4] = 1;
  client.sendRaw(old_version);
  client.tick();

  const DeviceServerStats after = server.stats();
  const auto dropped = [&](DropReason r) {
    return after.drops[static_cast<std::size_t>(r)] - before.drops[static_cast<std::size_t>(r)];
  };
  EXPECT_EQ(dropped(DropReason::kReplayed), 1u);
  EXPECT_EQ(dropped(DropReason::kOutOfOrder), 1u);
  EXPECT_EQ(dropped(DropReason::kWrongSession), 1u);
  EXPECT_EQ(dropped(DropReason::kBadMac), 1u);
  EXPECT_EQ(dropped(DropReason::kBadSize), 2u);
  EXPECT_EQ(dropped(DropReason::kBadHeader), 1u);
  EXPECT_EQ(dropped(DropReason::kBadValue), 2u);
  EXPECT_EQ(dropped(DropReason::kBadVersion), 1u);
  EXPECT_EQ(after.commands_applied, before.commands_applied);
  EXPECT_EQ(server.commandedForce(), good);
  EXPECT_LT(server.appliedForce().norm(), 1.0);  // never the evil 15.6 N, and ramping in

  // The HELLO that opened this session, replayed: from this address a replay (the session is
  // confirmed), from another address only a COOKIE for that address. No new session either way.
  client.sendRaw(opening);
  wire::UdpSocket intruder = wire::UdpSocket::connected(server.endpoint());
  ASSERT_TRUE(intruder.send(opening));
  client.tick();
  EXPECT_EQ(server.stats().sessions, 1u);
  EXPECT_EQ(server.stats().drops[static_cast<std::size_t>(DropReason::kReplayed)] -
                before.drops[static_cast<std::size_t>(DropReason::kReplayed)],
            2u);
  EXPECT_EQ(server.stats().cookies_sent, before.cookies_sent + 1);
  EXPECT_TRUE(server.sessionLive());
}

// Issue 40, items 1 and 6: no answer is larger than the packet that asked; a recorded HELLO
// opens nothing once its cookie's two seconds are over. (More recorded sessions than the
// responder remembers nonces of: tests/wire/link_session_test.cpp, on a simulated clock.)
TEST(DeviceServer, NoAnswerIsLargerThanItsHelloAndRecordedHellosCannotKeepAClientOut) {
  Rig rig;
  DeviceServer server(rig.config());
  RawClient recorder{rig, server};
  // 20 sessions opened and closed by a key holder, their opening HELLOs recorded.
  std::vector<std::vector<std::uint8_t>> recorded;
  for (std::uint8_t n = 0; n < 20; ++n) {
    recorded.push_back(recorder.handshake({n, 0xAA}));
    recorder.bye(1);
  }
  // Within the cookie's life the nonces are remembered; after it, every replay only gets a
  // COOKIE of 96 bytes for its 216, and a real client opens its session whenever it asks.
  std::this_thread::sleep_for(std::chrono::milliseconds(2100));
  const DeviceServerStats before = server.stats();
  RawClient attacker{rig, server};
  std::size_t answers = 0;
  for (const auto& hello : recorded) {
    attacker.sendRaw(hello);
    attacker.tick();
    wire::PacketBuffer buffer{};
    wire::Received rx;
    while (attacker.socket.receive(buffer, rx) == wire::ReceiveStatus::kPacket) {
      ++answers;
      EXPECT_LE(rx.size, hello.size());
    }
  }
  EXPECT_EQ(answers, recorded.size());
  EXPECT_EQ(server.stats().sessions, before.sessions);
  EXPECT_EQ(server.stats().cookies_sent, before.cookies_sent + recorded.size());
  RawClient real{rig, server};
  real.handshake({0xEE});
  EXPECT_EQ(server.stats().sessions, before.sessions + 1);
  EXPECT_TRUE(server.sessionLive());
}

// Issue 40, item 5: a fault the server's safety path latched (here a device error of the fake
// vendor SDK) survives the session it happened in and every later one.
TEST(DeviceServer, ALatchedDeviceErrorSurvivesANewSession) {
  Rig rig;
  const std::string plugin =
      "plugin:" + std::string(test::builtFile("HATTR_FAKE_VENDOR_PLUGIN")) + "?clock=host&error_after=20";
  DeviceServer server(rig.config(plugin));
  {
    RawClient first{rig, server};
    first.handshake({1});
    first.sendRaw(first.command(1, Vec3::Zero(), first.session_id));
    for (int i = 0; i < 40; ++i) first.tick();
    ASSERT_NE(server.loop().safety().fault(), servo::SafetyFault::kNone);
    ASSERT_EQ(server.stats().faults, 1u);
    first.bye(2);
  }
  RawClient second{rig, server};
  second.handshake({2});
  second.sendRaw(second.command(1, Vec3(0.5, 0.0, 0.0), second.session_id));
  for (int i = 0; i < 5; ++i) second.tick();
  EXPECT_EQ(server.stats().sessions, 2u);
  EXPECT_NE(server.loop().safety().fault(), servo::SafetyFault::kNone);
  EXPECT_EQ(server.stats().faults, 1u) << "the fault was cleared and latched again: a new session cleared it";
  EXPECT_EQ(server.appliedForce(), Vec3::Zero());
}

// Issue 40, item 4: reads late by more than the hold (overruns of 7 ms, below a stall) do not
// restart the hold: a dead server is reported at the first read after its last state aged.
TEST(DeviceServer, LateReadsDoNotMakeADeadServerLookAlive) {
  Rig rig;
  DeviceServer server(rig.config());
  server.start();
  auto client = rig.client(server);
  ASSERT_EQ(poll(*client, [](DeviceStatus) { return false; }, std::chrono::milliseconds(20)).second, DeviceStatus::kOk);
  server.loop().stop();  // silent, as if killed
  PenState pen;
  int ok_reads = 0;
  for (int i = 0; i < 5; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(7));
    if (client->read(std::chrono::nanoseconds(0), pen) == DeviceStatus::kOk) ++ok_reads;
  }
  EXPECT_EQ(ok_reads, 0) << "a read more than hold_ms (5 ms) after the last state said the link was fine";
}

// Issue 40, item 6: a reconnection compares the whole device (limits, mass, damping,
// capabilities, rate), not only the limits the old client compared.
TEST(DeviceServer, AServerBackWithAnotherDeviceMassIsRefusedAsAFault) {
  Rig rig;
  auto server = std::make_unique<DeviceServer>(rig.config());
  server->start();
  const std::string address = server->endpoint().text();
  auto client = rig.client(*server);
  ASSERT_EQ(poll(*client, [](DeviceStatus) { return false; }, std::chrono::milliseconds(10)).second, DeviceStatus::kOk);
  server.reset();
  server = std::make_unique<DeviceServer>(rig.config("sim://pen?mass_kg=0.2", address));
  server->start();
  const auto back = poll(*client, [](DeviceStatus s) { return s == DeviceStatus::kFault; }, std::chrono::seconds(1));
  EXPECT_EQ(back.second, DeviceStatus::kFault);
  EXPECT_THAT(client->faultReason(), HasSubstr("came back with another device"));
}

// Issue 40, item 3: 1 500 datagrams with a wrong MAC in a burst (150 a tick for 10 ticks of a
// 1 kHz session: the rate of the 6-11 ms burst) queued ahead of the client's COMMANDs
// leave no command waiting longer than the command timeout, and the server acts on the newest
// command: 20 runs of 20. The server is ticked by hand, back to back, so only the drain is measured.
TEST(DeviceServer, ABurstOfWrongMacDatagramsDoesNotStarveTheCommands) {
  HATTR_SKIP_UNDER_THREAD_SANITIZER(
      "the drain's budget is wall time and ThreadSanitizer makes each receive many times dearer; the release and "
      "ASan builds measure it");
  Rig rig;
  // The drain's budget is wall time: a host that holds this process up mid-tick (the watch sees
  // it) leaves the backlog to the next ticks, which is the budget doing its job, not the flood.
  (void)test::passesUnlessTheHostStalls([&](std::uint64_t& stalls) {
    const test::HostStallWatch watch(stalls, std::chrono::milliseconds(2));
    for (int run = 0; run < 20; ++run) {
      DeviceServer server(rig.config());
      RawClient client{rig, server};
      client.handshake({static_cast<std::uint8_t>(run)});
      wire::UdpSocket attacker = wire::UdpSocket::connected(server.endpoint());
      const auto forged = RawClient::encode({{.sender_time_ns = 1}, wire::HelloPayload{{9}}}, wire::randomKey());
      const std::uint64_t applied_before = server.stats().commands_applied;
      long largest_lag = 0;  // ticks between a command's sending and the tick that applied it
      constexpr int kTicks = 30;
      for (int tick = 1; tick <= kTicks; ++tick) {
        if (tick > 5 && tick <= 15) {
          for (int i = 0; i < 150; ++i) ASSERT_TRUE(attacker.send(forged));
        }
        const Vec3 force(1e-3 * tick, 0.0, 0.0);
        client.sendRaw(client.command(static_cast<std::uint64_t>(tick), force, client.session_id));
        client.tick();
        largest_lag = std::max(largest_lag, tick - std::lround(server.commandedForce().x() / 1e-3));
      }
      const DeviceServerStats stats = server.stats();
      EXPECT_EQ(stats.command_timeouts, 0u) << "run " << run;
      EXPECT_EQ(stats.commands_applied - applied_before, static_cast<std::uint64_t>(kTicks)) << "run " << run;
      // Each tick verifies a few (wrong MAC) and drops the rest of the flood unverified.
      EXPECT_EQ(stats.drops[static_cast<std::size_t>(DropReason::kBadMac)] +
                    stats.drops[static_cast<std::size_t>(DropReason::kRateLimited)],
                1500u)
          << "run " << run;
      EXPECT_LE(stats.drops[static_cast<std::size_t>(DropReason::kBadMac)],
                static_cast<std::uint64_t>(kTicks * wire::kMaxHandshakesPerPump))
          << "run " << run;
      EXPECT_EQ(server.commandedForce(), Vec3(1e-3 * kTicks, 0.0, 0.0)) << "run " << run;
      // The requirement: no command waits longer than the command timeout (10 ticks at 1 kHz).
      // Measured here in release: 0 or 1 tick; under ASan on a loaded host, up to 4.
      const long timeout_ticks = rig.config().command_timeout / server.loop().period();
      EXPECT_LT(largest_lag, timeout_ticks) << "run " << run;
      std::printf("run %d: a command was applied at most %ld ticks after it was sent\n", run, largest_lag);
    }
  });
}

TEST(DeviceServer, TheClientFaultsWithin20msOfASilentServerAndRecoversWhenItReturns) {
  (void)test::passesUnlessTheHostStalls([&](std::uint64_t& stalls) {
    // The times are measured by this process's threads: the host holding them up 5 ms (the
    // watch, or this thread between two polls) is a stall.
    const test::HostStallWatch watch(stalls, std::chrono::milliseconds(5));
    Rig rig;
    DeviceServer server(rig.config());
    server.start();
    auto client = rig.client(server);
    ASSERT_EQ(poll(*client, [](DeviceStatus) { return false; }, std::chrono::milliseconds(30)).second,
              DeviceStatus::kOk);

    // The server's loop stops without a word, as if the process had been killed.
    server.loop().stop();
    std::chrono::nanoseconds largest_gap{0};
    const auto [took, status] = poll(
        *client, [](DeviceStatus s) { return s == DeviceStatus::kDisconnected; }, std::chrono::milliseconds(200),
        Vec3::Zero(), &largest_gap);
    stalls += largest_gap > std::chrono::milliseconds(5) ? 1 : 0;
    ASSERT_EQ(status, DeviceStatus::kDisconnected);
    EXPECT_LE(took, std::chrono::milliseconds(20));
    EXPECT_THAT(client->faultReason(), HasSubstr("link lost: no state from " + server.endpoint().text() + " for "));

    // It stays away long enough for the client to give up on the session (50 ms), then comes
    // back: the client's new hello is answered and it is served again.
    (void)poll(*client, [](DeviceStatus) { return false; }, std::chrono::milliseconds(80));
    server.loop().start();
    const auto back = poll(*client, [](DeviceStatus s) { return s == DeviceStatus::kOk; }, std::chrono::seconds(1));
    EXPECT_EQ(back.second, DeviceStatus::kOk);
    // The old session's states come first; the answer to the hello queued behind a backlog of
    // commands follows within a few server ticks.
    (void)poll(*client, [](DeviceStatus) { return false; }, std::chrono::milliseconds(30));
    EXPECT_EQ(client->linkStats().reconnects, 1u);
    EXPECT_GE(client->linkStats().disconnected_reads, 1u);
  });
}

TEST(DeviceServer, AStoppedServerEndsTheSessionAndANewServerOnThePortServesTheClientAgain) {
  Rig rig;
  auto server = std::make_unique<DeviceServer>(rig.config());
  server->start();
  const std::string address = server->endpoint().text();
  auto client = rig.client(*server, nullptr, "&hold_ms=20");  // a brief hold-up of the server is bridged; the BYE is not
  ASSERT_EQ(poll(*client, [](DeviceStatus) { return false; }, std::chrono::milliseconds(10)).second,
            DeviceStatus::kOk);
  server.reset();  // says BYE
  const auto [took, status] =
      poll(*client, [](DeviceStatus s) { return s == DeviceStatus::kDisconnected; }, std::chrono::milliseconds(200));
  ASSERT_EQ(status, DeviceStatus::kDisconnected);
  EXPECT_LE(took, std::chrono::milliseconds(20));
  EXPECT_EQ(client->faultReason(), "link lost: the device server at " + address + " ended the session");

  server = std::make_unique<DeviceServer>(rig.config("sim://pen", address));
  server->start();
  const auto back = poll(*client, [](DeviceStatus s) { return s == DeviceStatus::kOk; }, std::chrono::seconds(1));
  EXPECT_EQ(back.second, DeviceStatus::kOk);
  EXPECT_EQ(server->stats().sessions, 1u);
}

TEST(DeviceServer, WithoutCommandsTheForceDropsToZeroAndASilentSessionEnds) {
  (void)test::passesUnlessTheHostStalls([&](std::uint64_t& stalls) {
    Rig rig;
    DeviceServerConfig config = rig.config();
    config.session_timeout = std::chrono::milliseconds(60);
    DeviceServer server(config);
    server.start();
    auto client = rig.client(server);
    (void)poll(*client, [](DeviceStatus) { return false; }, std::chrono::milliseconds(300), Vec3(0.4, 0.0, 0.0));
    const bool pushed = server.appliedForce().x() > 0.0;
    stalls = server.loop().counters().stalls.load();
    EXPECT_TRUE(pushed);
    const std::uint64_t timeouts_before = server.stats().command_timeouts;
    // The client goes quiet: after 10 ms zero force, after 60 ms no session.
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
    EXPECT_EQ(server.appliedForce(), Vec3::Zero());
    EXPECT_EQ(server.stats().command_timeouts, timeouts_before + 1);
    EXPECT_TRUE(server.sessionLive());
    std::this_thread::sleep_for(std::chrono::milliseconds(80));
    EXPECT_FALSE(server.sessionLive());
    EXPECT_EQ(server.stats().session_timeouts, 1u);
    stalls = server.loop().counters().stalls.load();
  });
}

/// Asks for a constant force, whatever the pen does.
class ConstantPush final : public GuidanceController {
 public:
  explicit ConstantPush(Vec3 force) : force_(std::move(force)) {}
  Vec3 compute(const PenState&, const ContactForces&, double) noexcept override { return force_; }

 private:
  Vec3 force_;
};

TEST(DeviceServer, EndToEndTheClientsHandWritesCirclesOnTheServersPenThroughBothSafetyPaths) {
  (void)test::passesUnlessTheHostStalls([&](std::uint64_t& stalls) {
    Rig rig;
    DeviceServer server(rig.config("sim://pen?continuous_force_N=0.5"));
    server.start();
    const Vec3 centre(0.0, 0.0, 0.005);
    device::CircleHand hand(centre, 0.015, 2.0, 0.0);
    auto client = rig.client(server, &hand, "&hold_ms=20");
    servo::ServoLoop loop(*client, servo::ServoConfig{.rate_hz = 1000.0,
                                                       .realtime = {.policy = servo::RealtimePolicy::kSkip}});
    ConstantPush push(Vec3(3.0, 0.0, 0.0));  // beyond the 0.5 N the server's pen takes
    loop.setGuidance(&push);
    loop.start();
    double largest_applied = 0.0;
    const auto start = Clock::now();
    // At least 0.7 s; longer (up to 3 s) while a stall of this machine keeps restarting the ramp.
    while (Clock::now() - start < std::chrono::milliseconds(700) ||
           (largest_applied <= 0.45 && Clock::now() - start < std::chrono::seconds(3))) {
      largest_applied = std::max(largest_applied, server.appliedForce().norm());
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    loop.stop();
    stalls = loop.counters().stalls.load() + server.loop().counters().stalls.load();
    EXPECT_EQ(loop.counters().faults.load(), 0u) << client->faultReason();

    // The pen goes round the hand's circle (the 0.5 N push shifts it by under 2 mm).
    TickSample s;
    double radius_sum = 0.0;
    int n = 0;
    double turned = 0.0;
    double last_angle = 0.0;
    bool first = true;
    while (loop.samples().tryPop(s)) {
      if (s.sample.t_s < 0.35) continue;
      const Vec3 d = s.sample.p_WT - centre;
      radius_sum += d.head<2>().norm();
      ++n;
      const double angle = std::atan2(d.y(), d.x());
      if (!first) turned += std::remainder(angle - last_angle, 2.0 * 3.141592653589793);
      last_angle = angle;
      first = false;
    }
    ASSERT_GT(n, 100);
    EXPECT_NEAR(radius_sum / n, 0.015, 0.004);
    EXPECT_GT(turned, 3.0);  // more than half a turn, counter-clockwise like the hand
    // Both safety paths clamp to the server's device: 0.5 N, and it got there.
    EXPECT_DOUBLE_EQ(client->limits().continuous_force_N, 0.5);
    EXPECT_LE(largest_applied, 0.5 + 1e-12);
    EXPECT_GT(largest_applied, 0.45);
    EXPECT_GT(client->linkStats().states_received, 0u);
  });
}

TEST(DeviceServer, TheServerTickAndTheClientsReadAndWriteNeverAllocateNorLock) {
  Rig rig;
  DeviceServer server(rig.config());
  // The handshake needs the server's ticks: a helper ticks it while the client opens.
  std::atomic<bool> opened{false};
  std::chrono::nanoseconds now{0};
  std::thread ticker([&] {
    while (!opened.load()) {
      now += server.loop().period();
      (void)server.loop().tick(now);
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
  });
  device::CircleHand hand(Vec3::Zero(), 0.01, 1.0, 0.5);
  std::unique_ptr<device::UdpDevice> client;
  try {
    client = rig.client(server, &hand);
  } catch (...) {
    opened = true;
    ticker.join();
    throw;
  }
  opened = true;
  ticker.join();

  PenState pen;
  const auto bad = std::vector<std::uint8_t>(100, 1);
  wire::UdpSocket noise = wire::UdpSocket::connected(server.endpoint());
  const test::NoAllocationScope scope;
  for (int i = 0; i < 2000; ++i) {
    now += server.loop().period();
    (void)server.loop().tick(now);
    (void)client->read(now, pen);
    (void)client->write(Vec3(0.1, 0.0, 0.0));
    if (i % 100 == 0) (void)noise.send(bad);  // drops are counted without allocating too
  }
  EXPECT_EQ(scope.allocations(), 0u);
  if (test::lockHookActive()) {
    EXPECT_EQ(scope.locks(), 0u);
  }
  EXPECT_GT(server.stats().commands_applied, 1000u);
  EXPECT_GE(server.stats().drops[static_cast<std::size_t>(DropReason::kBadHeader)], 20u);
}

}  // namespace
}  // namespace hattr::net
