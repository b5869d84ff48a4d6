// The wire protocol's packets and keys: exact round trips, the MAC over every byte, drops by
// reason, the sequence window, direction keys, key files and udp:// URIs.

#include "hattr/wire/packet.hpp"

#include <sys/stat.h>

#include <cmath>
#include <limits>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/device/udp_device.hpp"
#include "hattr/wire/udp_socket.hpp"
#include "support/test_support.hpp"

namespace hattr::wire {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::Not;

AuthKey keyOf(std::uint8_t first) {
  std::array<std::uint8_t, kKeySize> bytes{};
  for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<std::uint8_t>(first + 7 * i);
  return AuthKey(bytes);
}

// One packet of every type with awkward, distinct values in every field.
std::vector<Packet> everyPacketType() {
  const PacketHeader header{.session_id = 0x0102030405060708ull, .sequence = 0xfedcba9876543210ull,
                            .sender_time_ns = 123456789012345};
  Nonce nonce{};
  for (std::size_t i = 0; i < nonce.size(); ++i) nonce[i] = static_cast<std::uint8_t>(0xa0 + i);

  WelcomePayload welcome;
  welcome.nonce = nonce;
  welcome.rate_hz = 4000.0;
  welcome.session_timeout_ns = 500'000'000;
  welcome.command_timeout_ns = 10'000'000;
  welcome.capabilities = {.force_sensor = true, .pressure = false, .tilt = true};
  welcome.limits.degrees_of_freedom = 6;
  welcome.limits.workspace_min_m = Vec3(-0.1, -0.2, -0.3);
  welcome.limits.workspace_max_m = Vec3(0.1, 0.2, 0.3);
  welcome.limits.peak_force_N = 8.5;
  welcome.limits.continuous_force_N = 1.25e-3;
  welcome.limits.max_stiffness_N_per_m = 2345.0;
  welcome.limits.max_damping_N_s_per_m = 6.5;
  welcome.limits.nominal_rate_hz = 4000.0;
  welcome.limits.mass_kg = 0.075;
  welcome.limits.damping_N_s_per_m = 1e-300;

  StatePayload state;
  state.pen.t_s = 12.5;
  state.pen.p_WT = Vec3(0.01, -0.02, 5e-324);
  state.pen.v_WT = Vec3(-0.5, 0.25, -0.0);
  state.pen.buttons = 0x80000001u;
  state.pen.has_force = true;
  state.pen.f_measured_W = Vec3(1.0, 2.0, -3.0);
  state.pen.has_pressure = false;
  state.pen.pressure_raw = 4095.0;
  state.pen.has_tilt = true;
  state.pen.azimuth_rad = 2.356;
  state.pen.altitude_rad = 1.047;
  state.f_applied_W = Vec3(0.1, 0.2, 0.3);
  state.echo_sender_time_ns = 987654321;
  state.hold_ns = 12345;
  state.echo_sequence = 42;
  state.device_status = DeviceStatus::kFault;
  state.server_flags = kServerNoCommand | kServerSafetyFault;

  CommandPayload command;
  command.f_on_pen_W = Vec3(-1.5, 0.75, 1e-12);
  command.has_hand = true;
  command.hand.p_target_W = Vec3(0.015, 0.0, 0.003);
  command.hand.v_target_W = Vec3(0.0, 0.094, 0.0);
  command.hand.press_N = 1.2;
  command.hand.azimuth_rad = -1.0;
  command.hand.altitude_rad = 0.9;
  command.hand.pen_down = true;

  PeerPayload peer;
  peer.t_s = 12.5;
  peer.p_WT = Vec3(0.01, -0.02, 0.001);
  peer.v_WT = Vec3(0.1, 0.05, -0.002);
  peer.f_user_W = Vec3(0.2, -0.1, -1.3);
  peer.f_coupling_W = Vec3(-0.4, 0.3, 0.0);
  peer.energy_in_J = 0.125;
  peer.energy_out_J = 0.0625;
  peer.echo_sender_time_ns = 123456789;
  peer.hold_ns = 4321;
  peer.coupling = 3;
  peer.flags = kPeerPenDown | kPeerLinkUp;

  Cookie cookie{};
  for (std::size_t i = 0; i < cookie.size(); ++i) cookie[i] = static_cast<std::uint8_t>(0x30 + 3 * i);
  return {{header, HelloPayload{nonce, cookie}}, {header, welcome}, {header, BusyPayload{nonce}},
          {header, state},                      {header, command}, {header, ByePayload{7}},
          {header, peer},                       {header, CookiePayload{nonce, cookie}}};
}

bool samePen(const PenState& a, const PenState& b) {
  return a.t_s == b.t_s && a.p_WT == b.p_WT && a.v_WT == b.v_WT && a.buttons == b.buttons &&
         a.has_force == b.has_force && a.f_measured_W == b.f_measured_W && a.has_pressure == b.has_pressure &&
         a.pressure_raw == b.pressure_raw && a.has_tilt == b.has_tilt && a.azimuth_rad == b.azimuth_rad &&
         a.altitude_rad == b.altitude_rad;
}

bool samePayload(const Payload& a, const Payload& b) {
  if (a.index() != b.index()) return false;
  if (const auto* x = std::get_if<HelloPayload>(&a)) {
    return x->nonce == std::get<HelloPayload>(b).nonce && x->cookie == std::get<HelloPayload>(b).cookie;
  }
  if (const auto* x = std::get_if<CookiePayload>(&a)) {
    return x->nonce == std::get<CookiePayload>(b).nonce && x->cookie == std::get<CookiePayload>(b).cookie;
  }
  if (const auto* x = std::get_if<BusyPayload>(&a)) return x->nonce == std::get<BusyPayload>(b).nonce;
  if (const auto* x = std::get_if<ByePayload>(&a)) return x->reason == std::get<ByePayload>(b).reason;
  if (const auto* x = std::get_if<PeerPayload>(&a)) {
    const auto& y = std::get<PeerPayload>(b);
    return x->t_s == y.t_s && x->p_WT == y.p_WT && x->v_WT == y.v_WT && x->f_user_W == y.f_user_W &&
           x->f_coupling_W == y.f_coupling_W && x->energy_in_J == y.energy_in_J && x->energy_out_J == y.energy_out_J &&
           x->echo_sender_time_ns == y.echo_sender_time_ns && x->hold_ns == y.hold_ns && x->coupling == y.coupling &&
           x->flags == y.flags;
  }
  if (const auto* x = std::get_if<WelcomePayload>(&a)) {
    const auto& y = std::get<WelcomePayload>(b);
    return x->nonce == y.nonce && x->rate_hz == y.rate_hz &&
           x->session_timeout_ns == y.session_timeout_ns && x->command_timeout_ns == y.command_timeout_ns &&
           x->capabilities.force_sensor == y.capabilities.force_sensor &&
           x->capabilities.pressure == y.capabilities.pressure && x->capabilities.tilt == y.capabilities.tilt &&
           x->limits == y.limits;
  }
  if (const auto* x = std::get_if<StatePayload>(&a)) {
    const auto& y = std::get<StatePayload>(b);
    return samePen(x->pen, y.pen) && x->f_applied_W == y.f_applied_W &&
           x->echo_sender_time_ns == y.echo_sender_time_ns && x->hold_ns == y.hold_ns &&
           x->echo_sequence == y.echo_sequence && x->device_status == y.device_status &&
           x->server_flags == y.server_flags;
  }
  const auto& x = std::get<CommandPayload>(a);
  const auto& y = std::get<CommandPayload>(b);
  return x.f_on_pen_W == y.f_on_pen_W && x.has_hand == y.has_hand && x.hand.p_target_W == y.hand.p_target_W &&
         x.hand.v_target_W == y.hand.v_target_W && x.hand.press_N == y.hand.press_N &&
         x.hand.azimuth_rad == y.hand.azimuth_rad && x.hand.altitude_rad == y.hand.altitude_rad &&
         x.hand.pen_down == y.hand.pen_down;
}

TEST(NetProtocol, EveryPacketTypeRoundTripsBitForBit) {
  const AuthKey key = keyOf(1);
  for (const Packet& packet : everyPacketType()) {
    PacketBuffer buffer{};
    const std::size_t size = encodePacket(packet, key, buffer);
    Packet decoded;
    DropReason why{};
    ASSERT_TRUE(decodePacket(std::span(buffer.data(), size), key, decoded, why))
        << "type " << packet.payload.index() << " dropped as " << dropReasonName(why);
    EXPECT_EQ(decoded.header.session_id, packet.header.session_id);
    EXPECT_EQ(decoded.header.sequence, packet.header.sequence);
    EXPECT_EQ(decoded.header.sender_time_ns, packet.header.sender_time_ns);
    EXPECT_EQ(size, packetSize(decoded.header.type));
    EXPECT_TRUE(samePayload(decoded.payload, packet.payload)) << "type " << packet.payload.index();
  }
}

TEST(NetProtocol, PacketsHaveFixedSizesAndAnExplicitLittleEndianHeader) {
  EXPECT_EQ(packetSize(PacketType::kHello), 216u);  // padded to the WELCOME's size: no answer is larger
  EXPECT_EQ(packetSize(PacketType::kCookie), 96u);
  EXPECT_EQ(packetSize(PacketType::kWelcome), 216u);
  EXPECT_EQ(packetSize(PacketType::kBusy), 80u);
  EXPECT_EQ(packetSize(PacketType::kState), 232u);
  EXPECT_EQ(packetSize(PacketType::kCommand), 168u);
  EXPECT_EQ(packetSize(PacketType::kBye), 72u);
  EXPECT_EQ(packetSize(PacketType::kPeer), 208u);
  EXPECT_EQ(packetSize(static_cast<PacketType>(99)), 0u);

  const Packet command = everyPacketType()[4];
  PacketBuffer b{};
  ASSERT_EQ(encodePacket(command, keyOf(1), b), 168u);
  const std::vector<std::uint8_t> head(b.begin(), b.begin() + 32);
  const std::vector<std::uint8_t> expected = {
      'H', 'A', 'T', 'R', 2, 0, 5, 0,                     // magic, version 2, type COMMAND
      0x08, 0x07, 0x06, 0x05, 0x04, 0x03, 0x02, 0x01,     // session id
      0x10, 0x32, 0x54, 0x76, 0x98, 0xba, 0xdc, 0xfe,     // sequence
  };
  EXPECT_EQ(std::vector<std::uint8_t>(head.begin(), head.begin() + 24), expected);
  // The force's x (-1.5) is the first payload field: IEEE 754 binary64, little-endian.
  const std::vector<std::uint8_t> minus_one_and_a_half = {0, 0, 0, 0, 0, 0, 0xf8, 0xbf};
  EXPECT_EQ(std::vector<std::uint8_t>(b.begin() + 32, b.begin() + 40), minus_one_and_a_half);
}

TEST(NetProtocol, EveryTamperedByteFailsTheMacAndTheDecode) {
  const AuthKey key = keyOf(1);
  for (const Packet& packet : everyPacketType()) {
    PacketBuffer buffer{};
    const std::size_t size = encodePacket(packet, key, buffer);
    for (std::size_t i = 0; i < size; ++i) {
      for (const std::uint8_t flip : {std::uint8_t{0x01}, std::uint8_t{0x80}}) {
        PacketBuffer tampered = buffer;
        tampered[i] ^= flip;
        const std::span<const std::uint8_t> datagram(tampered.data(), size);
        EXPECT_FALSE(verifyMac(datagram, key)) << "type " << packet.payload.index() << " byte " << i;
        Packet decoded;
        DropReason why{};
        ASSERT_FALSE(decodePacket(datagram, key, decoded, why)) << "type " << packet.payload.index() << " byte " << i;
        // Bytes beyond magic, version and type reach the MAC check and fail it.
        if (i >= 8) {
          EXPECT_EQ(why, DropReason::kBadMac) << "byte " << i << ": " << dropReasonName(why);
        } else if (i < 4) {
          EXPECT_EQ(why, DropReason::kBadHeader) << "byte " << i;
        } else if (i < 6) {
          EXPECT_EQ(why, DropReason::kBadVersion) << "byte " << i;
        }
      }
    }
  }
}

TEST(NetProtocol, WrongSizeGarbageAnotherKeyAndNonFiniteValuesAreDroppedWithTheirReason) {
  const AuthKey key = keyOf(1);
  const Packet command = everyPacketType()[4];
  PacketBuffer buffer{};
  const std::size_t size = encodePacket(command, key, buffer);
  Packet out;
  DropReason why{};

  EXPECT_FALSE(decodePacket(std::span(buffer.data(), size - 1), key, out, why));
  EXPECT_EQ(why, DropReason::kBadSize);
  EXPECT_FALSE(decodePacket(std::span(buffer.data(), size + 1), key, out, why));
  EXPECT_EQ(why, DropReason::kBadSize);
  EXPECT_FALSE(decodePacket(std::span(buffer.data(), 10), key, out, why));
  EXPECT_EQ(why, DropReason::kBadSize);

  std::array<std::uint8_t, 168> garbage{};
  for (std::size_t i = 0; i < garbage.size(); ++i) garbage[i] = static_cast<std::uint8_t>(i * 37 + 11);
  EXPECT_FALSE(decodePacket(garbage, key, out, why));
  EXPECT_EQ(why, DropReason::kBadHeader);
  std::copy(buffer.begin(), buffer.begin() + 8, garbage.begin());  // a plausible header, garbage after it
  EXPECT_FALSE(decodePacket(garbage, key, out, why));
  EXPECT_EQ(why, DropReason::kBadMac);

  EXPECT_FALSE(decodePacket(std::span(buffer.data(), size), keyOf(2), out, why));
  EXPECT_EQ(why, DropReason::kBadMac);

  PacketBuffer wrong_version = buffer;
  wrong_version[4] = 1;  // a hattr of protocol version 1
  EXPECT_FALSE(decodePacket(std::span(wrong_version.data(), size), key, out, why));
  EXPECT_EQ(why, DropReason::kBadVersion);

  // Authentic, but a hold of more than a second (a number that would overflow arithmetic).
  Packet held = everyPacketType()[3];
  std::get<StatePayload>(held.payload).hold_ns = kMaxHoldNs + 1;
  const std::size_t held_size = encodePacket(held, key, buffer);
  EXPECT_FALSE(decodePacket(std::span(buffer.data(), held_size), key, out, why));
  EXPECT_EQ(why, DropReason::kBadValue);

  Packet nan_force = command;
  std::get<CommandPayload>(nan_force.payload).f_on_pen_W.x() = std::numeric_limits<double>::quiet_NaN();
  const std::size_t nan_size = encodePacket(nan_force, key, buffer);
  EXPECT_FALSE(decodePacket(std::span(buffer.data(), nan_size), key, out, why));
  EXPECT_EQ(why, DropReason::kBadValue);
}

TEST(SequenceCheck, AcceptsOnlyStrictlyIncreasingNumbersAndCountsGapsAsLost) {
  SequenceCheck check;
  DropReason why{};
  EXPECT_TRUE(check.accept(1, why));
  EXPECT_TRUE(check.accept(2, why));
  EXPECT_FALSE(check.accept(2, why));
  EXPECT_EQ(why, DropReason::kReplayed);
  EXPECT_TRUE(check.accept(5, why));
  EXPECT_EQ(check.lost(), 2u);
  EXPECT_FALSE(check.accept(4, why));
  EXPECT_EQ(why, DropReason::kOutOfOrder);
  EXPECT_EQ(check.newest(), 5u);
  check.reset();
  EXPECT_TRUE(check.accept(1, why));
  EXPECT_EQ(check.lost(), 0u);
}

TEST(SequenceCheck, OneAuthenticNumberFarAheadCannotBlockTheDirection) {
  SequenceCheck check;
  DropReason why{};
  ASSERT_TRUE(check.accept(10, why));
  EXPECT_FALSE(check.accept(std::numeric_limits<std::uint64_t>::max(), why));
  EXPECT_EQ(why, DropReason::kBadValue);
  EXPECT_FALSE(check.accept(10 + kSequenceWindow + 1, why));
  EXPECT_EQ(why, DropReason::kBadValue);
  EXPECT_TRUE(check.accept(11, why));  // the real sender goes on
  EXPECT_TRUE(check.accept(11 + kSequenceWindow, why));
  EXPECT_EQ(check.lost(), kSequenceWindow - 1);
}

TEST(DirectionKeys, EachDirectionHasItsOwnKeySoAPacketNeverVerifiesTheOtherWay) {
  const AuthKey shared = keyOf(1);
  const DirectionKeys initiator = directionKeys(shared, Role::kInitiator);
  const DirectionKeys responder = directionKeys(shared, Role::kResponder);
  EXPECT_EQ(initiator.send.bytes(), responder.receive.bytes());
  EXPECT_EQ(initiator.receive.bytes(), responder.send.bytes());
  EXPECT_NE(initiator.send.bytes(), initiator.receive.bytes());
  EXPECT_NE(initiator.send.bytes(), shared.bytes());
  EXPECT_NE(directionKeys(keyOf(2), Role::kInitiator).send.bytes(), initiator.send.bytes());

  // A packet sent by one side, reflected back to it unchanged, fails its own MAC check.
  const Packet peer = everyPacketType()[6];
  PacketBuffer buffer{};
  const std::size_t size = encodePacket(peer, initiator.send, buffer);
  Packet out;
  DropReason why{};
  EXPECT_TRUE(decodePacket(std::span(buffer.data(), size), responder.receive, out, why));
  EXPECT_FALSE(decodePacket(std::span(buffer.data(), size), initiator.receive, out, why));
  EXPECT_EQ(why, DropReason::kBadMac);
}

// Issue 40, item 6: arrival times stay on CLOCK_MONOTONIC when the real-time clock (the only
// clock the kernel stamps datagrams by) steps.
TEST(UdpSocket, ArrivalTimesStayMonotonicWhenTheRealTimeClockSteps) {
  constexpr std::int64_t kSecond = 1'000'000'000;
  std::int64_t offset = 0;
  // Steady clocks: the arrival is the monotonic time less the datagram's age (300 µs).
  EXPECT_EQ(monotonicArrival(5 * kSecond, 900 * kSecond, 900 * kSecond - 300'000, offset), 5 * kSecond - 300'000);
  EXPECT_EQ(monotonicArrival(6 * kSecond, 901 * kSecond, 901 * kSecond - 100'000, offset), 6 * kSecond - 100'000);
  // The real-time clock steps back 10 s after a datagram was stamped: its age by that clock would
  // be negative; the arrival is the time of the receive.
  EXPECT_EQ(monotonicArrival(7 * kSecond, 892 * kSecond, 902 * kSecond - 50'000, offset), 7 * kSecond);
  // A step forward of 1 h between stamp and receive would make a fresh datagram an hour old.
  EXPECT_EQ(monotonicArrival(8 * kSecond, 893 * kSecond + 3600 * kSecond, 893 * kSecond, offset), 8 * kSecond);
  // Once steady again, ages are believed again.
  EXPECT_EQ(monotonicArrival(9 * kSecond, 4494 * kSecond, 4494 * kSecond - 20'000, offset), 9 * kSecond - 20'000);
}

TEST(KeyFile, ReadsSixtyFourHexCharactersWithOrWithoutANewline) {
  test::TempDir dir;
  const std::string hex = "000102030405060708090a0b0c0d0e0f101112131415161718191A1B1C1D1E1F";
  test::writeText(dir / "a.key", hex);
  test::writeText(dir / "b.key", hex + "\n");
  for (const char* name : {"a.key", "b.key"}) {
    ASSERT_EQ(::chmod((dir / name).c_str(), 0600), 0);
    const AuthKey key = readKeyFile(dir / name);
    for (std::size_t i = 0; i < kKeySize; ++i) EXPECT_EQ(key.bytes()[i], i) << name << " byte " << i;
  }
}

TEST(KeyFile, AnythingElseIsRefusedNamingTheFileWithoutShowingTheKey) {
  test::TempDir dir;
  const std::string hex = "000102030405060708090a0b0c0d0e0f101112131415161718191a1b1c1d1e1f";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"", "got 0 characters"},
      {hex.substr(0, 63), "got 63 characters"},
      {hex + "0", "got 65 characters"},
      {hex + "\n\n", "got 65 characters"},
      {std::string(" ").append(hex, 1), "not hexadecimal at position 1"},
      {std::string(hex, 0, 40).append("g").append(hex, 41), "not hexadecimal at position 41"},
      {hex + hex + hex, "got a longer file"},
  };
  for (const auto& [text, message] : cases) {
    test::writeText(dir / "bad.key", text);
    ASSERT_EQ(::chmod((dir / "bad.key").c_str(), 0600), 0);
    try {
      (void)readKeyFile(dir / "bad.key");
      ADD_FAILURE() << "accepted \"" << text << "\"";
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), AllOf(HasSubstr("bad.key"), HasSubstr("expected 64 hexadecimal characters"),
                                  HasSubstr(message), Not(HasSubstr("0a0b0c"))))
          << text;
    }
  }
  try {
    (void)readKeyFile(dir / "missing.key");
    ADD_FAILURE() << "a missing file was accepted";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("missing.key"), HasSubstr("cannot open")));
  }
}

TEST(KeyFile, WrittenKeysAreOwnerOnlyRandomAndNeverSilentlyReplaced) {
  test::TempDir dir;
  const auto file = dir / "k.key";
  writeKeyFile(file, randomKey(), false);
  struct stat info {};
  ASSERT_EQ(::stat(file.c_str(), &info), 0);
  EXPECT_EQ(info.st_mode & 0777, 0600u);
  EXPECT_EQ(test::readText(file).size(), 65u);
  const AuthKey first = readKeyFile(file);
  try {
    writeKeyFile(file, randomKey(), false);
    ADD_FAILURE() << "replaced without overwrite";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("k.key"), HasSubstr("exists already"), HasSubstr("--force")));
  }
  EXPECT_EQ(readKeyFile(file).bytes(), first.bytes());
  writeKeyFile(file, randomKey(), true);
  EXPECT_NE(readKeyFile(file).bytes(), first.bytes());
}

TEST(KeyFile, AKeyFileGroupOrOthersCanOpenIsRefusedAsSshRefusesAPrivateKey) {
  const test::TempDir dir;
  const auto file = dir / "open.key";
  writeKeyFile(file, randomKey(), false);
  for (const ::mode_t mode : {0640, 0604, 0644, 0660, 0620}) {
    ASSERT_EQ(::chmod(file.c_str(), mode), 0);
    try {
      (void)readKeyFile(file);
      ADD_FAILURE() << "accepted mode " << std::oct << mode;
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), AllOf(HasSubstr("open.key"), HasSubstr("mode 0600"), HasSubstr("open to group or others"),
                                  HasSubstr("chmod 600")));
    }
  }
  ASSERT_EQ(::chmod(file.c_str(), 0400), 0);
  EXPECT_NO_THROW((void)readKeyFile(file));
}

TEST(KeyFile, ReplacingAKeyNeverWritesThroughASymbolicLink) {
  const test::TempDir dir;
  const auto target = dir / "elsewhere.txt";
  test::writeText(target, "not a key\n");
  std::filesystem::create_symlink(target, dir / "link.key");
  try {
    writeKeyFile(dir / "link.key", randomKey(), true);
    ADD_FAILURE() << "wrote through a symbolic link";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("link.key"), HasSubstr("symbolic link")));
  }
  EXPECT_EQ(test::readText(target), "not a key\n");
}

TEST(UdpDeviceUri, KeysAreCheckedAndUnknownOnesListTheAcceptedOnes) {
  using device::parseDeviceUri;
  using device::udpDeviceParams;
  const auto params = udpDeviceParams(parseDeviceUri("udp://localhost:5000?key=/tmp/k&hold_ms=5&timeout_s=0.5"));
  EXPECT_EQ(params.server.text(), "127.0.0.1:5000");
  EXPECT_EQ(params.key_file, "/tmp/k");
  EXPECT_DOUBLE_EQ(params.hold_s, 0.005);
  EXPECT_DOUBLE_EQ(params.handshake_timeout_s, 0.5);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"udp://127.0.0.1:5000?key=k&colour=red", "unknown key \"colour\": expected one of key, hold_ms, timeout_s"},
      {"udp://127.0.0.1:5000", "missing key=FILE"},
      {"udp://127.0.0.1:5000?key=k&hold_ms=50", "key hold_ms: expected a number in [0.5, 20], got \"50\""},
      {"udp://example.org:5000?key=k", "host: expected an IPv4 address (like 127.0.0.1) or localhost, got \"example.org\""},
      {"udp://127.0.0.1:0?key=k", "port: expected a number in [1, 65535], got \"0\""},
      {"udp://127.0.0.1?key=k", "expected HOST:PORT"},
  };
  for (const auto& [uri, message] : cases) {
    try {
      (void)udpDeviceParams(parseDeviceUri(uri));
      ADD_FAILURE() << "accepted " << uri;
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr(message)) << uri;
    }
  }
}

}  // namespace
}  // namespace hattr::wire
