// The open pen's reference firmware, unmodified, under hattr-pen-emulator (simavr), spoken to
// byte by byte: its identity, its counts of bad packets, its watchdog.

#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "hattr/device/planar_pen.hpp"
#include "integration/openpen_test_support.hpp"

namespace hattr::test {
namespace {

using namespace std::chrono_literals;

hpen_identity handshake(ProtocolPort& port, std::uint32_t nonce) {
  port.hello(nonce);
  for (auto f = port.next(); f; f = port.next()) {
    if (f->event == HPEN_FRAME && f->type == HPEN_IDENTITY) {
      hpen_identity id{};
      hpen_decode_identity(f->payload.data(), &id);
      if (id.nonce == nonce) return id;
    }
  }
  ADD_FAILURE() << "no IDENTITY";
  return {};
}

TEST(OpenPenFirmware, IntroducesItselfWithTheReferenceBuildsConstants) {
  HATTR_SKIP_WITHOUT_OPEN_PEN();
  TempDir dir;
  PenEmulator emulator(dir, {"--hangups", "1", "--linger-ms", "0"});
  ASSERT_FALSE(emulator.pty().empty()) << "the emulator named no pty";
  ProtocolPort port(emulator.pty());
  const hpen_identity id = handshake(port, 77);
  const device::PlanarPenSpec ref = device::referencePlanarPen();
  EXPECT_EQ(std::string(id.model, strnlen(id.model, HPEN_MODEL_BYTES)), ref.model);
  EXPECT_EQ(id.state_rate_hz, 1000);
  EXPECT_EQ(id.watchdog_ms, 20);
  EXPECT_FLOAT_EQ(id.proximal_m, static_cast<float>(ref.geometry.proximal_m));
  EXPECT_FLOAT_EQ(id.distal_m, static_cast<float>(ref.geometry.distal_m));
  EXPECT_FLOAT_EQ(id.home_q0_rad, static_cast<float>(ref.home_q[0]));
  EXPECT_EQ(id.counts_per_joint_rev, 20000u);
  EXPECT_FLOAT_EQ(id.peak_torque_Nm, static_cast<float>(ref.peak_torque_Nm));
  EXPECT_EQ(id.status & HPEN_IDENTITY_HOMED, 0) << "not homed before the first START";
  // Homed once the encoders were zeroed, as a second HELLO says.
  port.start(HPEN_START_ZERO_ENCODERS);
  ASSERT_TRUE(port.nextState());
  EXPECT_EQ(handshake(port, 78).status & HPEN_IDENTITY_HOMED, HPEN_IDENTITY_HOMED);
  port.close();
  EXPECT_EQ(emulator.process().wait(), 0);
}

TEST(OpenPenFirmware, DropsAndCountsCorruptedOutOfSequenceAndWrongVersionPackets) {
  HATTR_SKIP_WITHOUT_OPEN_PEN();
  TempDir dir;
  PenEmulator emulator(dir, {"--hangups", "1", "--linger-ms", "0"});
  ProtocolPort port(emulator.pty());
  (void)handshake(port, 1);
  port.start(HPEN_START_ZERO_ENCODERS);
  // Each STATE answered by exactly one frame (the emulator in lockstep takes one answer a STATE),
  // one kind of bad packet per STATE, then good commands again.
  std::optional<hpen_state> s = port.nextState();
  ASSERT_TRUE(s);
  auto corrupted = port.command(s->seq, 1000, 1000, false);
  corrupted[7] ^= 0x01;
  port.sendBytes(corrupted);
  s = port.nextState();
  ASSERT_TRUE(s);
  port.command(static_cast<std::uint16_t>(s->seq - 5), 1000, 1000);  // answers a STATE long gone
  s = port.nextState();
  ASSERT_TRUE(s);
  const std::uint16_t answered = s->seq;
  port.command(answered, 1000, 1000);
  s = port.nextState();
  ASSERT_TRUE(s);
  port.command(answered, 1000, 1000);  // the STATE before answered again
  s = port.nextState();
  ASSERT_TRUE(s);
  const hpen_command c{.seq = s->seq, .effort0 = 0, .effort1 = 0, .flags = HPEN_COMMAND_ENABLE};
  std::uint8_t p[HPEN_COMMAND_BYTES];
  hpen_encode_command(p, &c);
  port.send(HPEN_COMMAND, p, HPEN_COMMAND_BYTES, HPEN_PROTOCOL_VERSION + 1);
  for (int i = 0; i < 5; ++i) {
    s = port.nextState();
    ASSERT_TRUE(s);
    port.command(s->seq, 1000, 1000);
  }
  s = port.nextState();
  ASSERT_TRUE(s);
  EXPECT_EQ(s->rx_malformed, 1);
  EXPECT_EQ(s->rx_out_of_sequence, 2);
  EXPECT_EQ(s->rx_wrong_version, 1);
  EXPECT_EQ(s->flags & HPEN_STATE_MOTORS_ON, HPEN_STATE_MOTORS_ON) << "good commands still drive the motors";
  EXPECT_EQ(s->watchdog_trips, 0);
}

TEST(OpenPenFirmware, ItsWatchdogStopsTheMotorsWhenTheHostStopsSending) {
  HATTR_SKIP_WITHOUT_OPEN_PEN();
  TempDir dir;
  // The chip waits only 20 ms (wall clock) for an answer, so it runs on once the host goes quiet.
  PenEmulator emulator(dir, {"--reply-timeout-ms", "20", "--hangups", "1", "--linger-ms", "0", "--trace",
                             (dir / "trace.csv").string()});
  ProtocolPort port(emulator.pty());
  (void)handshake(port, 5);
  port.start(HPEN_START_ZERO_ENCODERS);
  std::uint32_t last_command_us = 0;
  for (int i = 0; i < 100; ++i) {
    const auto s = port.nextState();
    ASSERT_TRUE(s);
    port.command(s->seq, 6000, -6000);
    last_command_us = s->time_us;
  }
  // Silence: the STATEs go on; the motors go off 20 ms after the last command.
  std::optional<hpen_state> tripped;
  for (int i = 0; i < 60 && !tripped; ++i) {
    const auto s = port.nextState();
    ASSERT_TRUE(s);
    if ((s->flags & HPEN_STATE_WATCHDOG) != 0) tripped = s;
    else EXPECT_EQ(s->flags & HPEN_STATE_MOTORS_ON, HPEN_STATE_MOTORS_ON) << "at " << s->time_us << " µs";
  }
  ASSERT_TRUE(tripped) << "the watchdog never tripped";
  EXPECT_EQ(tripped->flags & HPEN_STATE_MOTORS_ON, 0);
  EXPECT_EQ(tripped->watchdog_trips, 1);
  const double after_ms = (tripped->time_us - last_command_us) * 1e-3;
  EXPECT_GE(after_ms, 19.0);
  EXPECT_LE(after_ms, 22.0) << "the 20 ms watchdog (the command arrives within the period after its STATE)";
  // Ten more silent milliseconds, so the plant's trace shows what the motors did after the trip.
  for (int i = 0; i < 10; ++i) ASSERT_TRUE(port.nextState());
  port.close();
  ASSERT_EQ(emulator.process().wait(), 0);

  // The plant saw it: torque while commanded, none from the trip on.
  std::ifstream trace(dir / "trace.csv");
  std::string line;
  std::getline(trace, line);
  double driven_max = 0.0, after_max = 0.0;
  int rows_after = 0;
  const double trip_s = tripped->time_us * 1e-6;
  while (std::getline(trace, line)) {
    std::stringstream row(line);
    std::vector<double> v;
    for (std::string cell; std::getline(row, cell, ',');) v.push_back(std::stod(cell));
    const double torque = std::max(std::abs(v[6]), std::abs(v[7]));
    if (v[0] > 0.03 && v[0] < trip_s - 0.03) driven_max = std::max(driven_max, torque);
    if (v[0] > trip_s + 0.002) {
      after_max = std::max(after_max, torque);
      ++rows_after;
    }
  }
  EXPECT_GT(driven_max, 0.01);
  EXPECT_GE(rows_after, 5) << "the trace covers the time after the trip";
  EXPECT_EQ(after_max, 0.0);
}

}  // namespace
}  // namespace hattr::test
