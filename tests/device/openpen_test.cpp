// The open pen's shared protocol codec (include/hattr/openpen/protocol.h), the five-bar's
// kinematics, the force-to-effort map and the planar plant, on the host.

#include <cmath>
#include <cstring>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/device/five_bar.hpp"
#include "hattr/device/planar_pen.hpp"
#include "hattr/device/simulated_planar_device.hpp"
#include "hattr/openpen/protocol.h"

namespace hattr::device {
namespace {

/// Every event the parser gives for `bytes`, with the frame types it completed.
std::vector<std::pair<hpen_event, int>> feedAll(hpen_parser& parser, const std::vector<std::uint8_t>& bytes) {
  std::vector<std::pair<hpen_event, int>> events;
  for (std::uint8_t b : bytes) {
    const hpen_event e = hpen_parser_feed(&parser, b);
    if (e != HPEN_NONE) events.emplace_back(e, hpen_parser_type(&parser));
  }
  return events;
}

std::vector<std::uint8_t> commandFrame(std::uint16_t seq, std::int16_t e0, std::int16_t e1, std::uint8_t version = HPEN_PROTOCOL_VERSION) {
  const hpen_command c{.seq = seq, .effort0 = e0, .effort1 = e1, .flags = HPEN_COMMAND_ENABLE};
  std::uint8_t payload[HPEN_COMMAND_BYTES];
  hpen_encode_command(payload, &c);
  std::uint8_t frame[HPEN_MAX_FRAME_BYTES];
  const std::uint8_t n = hpen_frame(frame, version, HPEN_COMMAND, payload, HPEN_COMMAND_BYTES);
  return {frame, frame + n};
}

TEST(OpenPenProtocol, CrcIsCcittFalse) {
  // The check value of CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF): "123456789" -> 0x29B1.
  const char* text = "123456789";
  EXPECT_EQ(hpen_crc(reinterpret_cast<const std::uint8_t*>(text), 9), 0x29B1);
}

TEST(OpenPenProtocol, EveryMessageSurvivesItsRoundTrip) {
  hpen_state s{};  // zero-initialized, padding too, so the two compare as bytes
  s.seq = 65535;
  s.time_us = 4294967000u;
  s.count0 = -123456;
  s.count1 = 2000000000;
  s.sensor = 1023;
  s.flags = HPEN_STATE_MOTORS_ON | HPEN_STATE_BUTTON;
  s.rx_malformed = 1;
  s.rx_out_of_sequence = 2;
  s.rx_wrong_version = 3;
  s.watchdog_trips = 4;
  s.tx_skipped = 5;
  std::uint8_t p[HPEN_MAX_PAYLOAD_BYTES];
  hpen_encode_state(p, &s);
  hpen_state back{};
  hpen_decode_state(p, &back);
  EXPECT_EQ(std::memcmp(&s, &back, sizeof s), 0);

  hpen_identity id{};
  id.nonce = 0xDEADBEEF;
  id.firmware_build = 7;
  std::memcpy(id.model, "openpen-5bar", HPEN_MODEL_BYTES);
  id.state_rate_hz = 1000;
  id.watchdog_ms = 20;
  id.base_separation_m = 0.04f;
  id.proximal_m = 0.08f;
  id.distal_m = 0.1f;
  id.home_q0_rad = 2.3f;
  id.home_q1_rad = 0.8f;
  id.counts_per_joint_rev = 20000;
  id.peak_torque_Nm = 0.693f;
  id.continuous_torque_Nm = 0.277f;
  id.sensor_N_per_count = 0.010851f;
  id.sensor_zero_count = 102;
  id.sensor_max_count = 1023;
  id.motor_sign = 2;
  hpen_encode_identity(p, &id);
  hpen_identity id_back{};
  hpen_decode_identity(p, &id_back);
  EXPECT_EQ(std::memcmp(&id, &id_back, sizeof id), 0);

  // Little-endian on the wire whatever the host: the seq's low byte first.
  const auto frame = commandFrame(0x1234, -32767, 32767);
  ASSERT_EQ(frame.size(), HPEN_HEADER_BYTES + HPEN_COMMAND_BYTES + HPEN_CRC_BYTES);
  EXPECT_EQ(frame[5], 0x34);
  EXPECT_EQ(frame[6], 0x12);
  hpen_command c{};
  hpen_decode_command(frame.data() + HPEN_HEADER_BYTES, &c);
  EXPECT_EQ(c.seq, 0x1234);
  EXPECT_EQ(c.effort0, -32767);
  EXPECT_EQ(c.effort1, 32767);
}

TEST(OpenPenProtocol, TheParserFindsFramesInNoiseAndDropsBadOnes) {
  hpen_parser parser;
  hpen_parser_reset(&parser);
  std::vector<std::uint8_t> stream = {0x00, 0xA5, 0xA5, 0x17};  // noise, a false start
  const auto good = commandFrame(1, 10, -10);
  stream.insert(stream.end(), good.begin(), good.end());
  auto corrupted = commandFrame(2, 10, -10);
  corrupted[7] ^= 0x40;  // a payload bit flipped: the CRC no longer matches
  stream.insert(stream.end(), corrupted.begin(), corrupted.end());
  auto bad_length = commandFrame(3, 0, 0);
  bad_length[4] = 60;  // a length the type does not have: refused at the header
  stream.insert(stream.end(), bad_length.begin(), bad_length.begin() + 5);
  const auto other_version = commandFrame(4, 0, 0, 9);
  stream.insert(stream.end(), other_version.begin(), other_version.end());
  stream.insert(stream.end(), good.begin(), good.end());

  const auto events = feedAll(parser, stream);
  const std::vector<std::pair<hpen_event, int>> expected = {{HPEN_FRAME, HPEN_COMMAND},
                                                            {HPEN_BAD_CRC, HPEN_COMMAND},
                                                            {HPEN_BAD_LENGTH, HPEN_NONE},
                                                            {HPEN_WRONG_VERSION, HPEN_COMMAND},
                                                            {HPEN_FRAME, HPEN_COMMAND}};
  ASSERT_EQ(events.size(), expected.size());
  for (std::size_t i = 0; i < events.size(); ++i) {
    EXPECT_EQ(events[i].first, expected[i].first) << "event " << i;
    if (expected[i].first != HPEN_BAD_LENGTH) {
      EXPECT_EQ(events[i].second, expected[i].second) << "event " << i;
    }
  }
  EXPECT_EQ(hpen_parser_version(&parser), HPEN_PROTOCOL_VERSION);
}

TEST(OpenPenProtocol, ALostByteCostsOnlyItsOwnFrame) {
  // The short frame swallows the next one's first sync byte; the receiver finds it again.
  hpen_parser parser;
  hpen_parser_reset(&parser);
  auto short_frame = commandFrame(1, 10, -10);
  short_frame.erase(short_frame.begin() + 8);
  std::vector<std::uint8_t> stream = short_frame;
  for (const std::uint16_t seq : {std::uint16_t{2}, std::uint16_t{3}}) {
    const auto next = commandFrame(seq, 0, 0);
    stream.insert(stream.end(), next.begin(), next.end());
  }
  const auto events = feedAll(parser, stream);
  ASSERT_EQ(events.size(), 3u);
  EXPECT_EQ(events[0].first, HPEN_BAD_CRC);
  EXPECT_EQ(events[1].first, HPEN_FRAME) << "the frame after the short one";
  EXPECT_EQ(events[2].first, HPEN_FRAME);
  hpen_command c{};
  hpen_decode_command(hpen_parser_payload(&parser), &c);
  EXPECT_EQ(c.seq, 3);
}

TEST(FiveBar, ForwardAndInverseAgreeAndTheJacobianIsTheDerivative) {
  const FiveBarGeometry g;
  const PlanarPenSpec spec = referencePlanarPen();
  Vec2 home;
  ASSERT_TRUE(fiveBarForward(g, spec.home_q, home));
  EXPECT_NEAR(home.x(), 0.0, 1e-9);  // symmetric home pose: the pen on the middle line
  EXPECT_NEAR(home.y(), 0.1209, 1e-4);  // 121 mm in front of the base line (firmware/openpen/config.h)
  EXPECT_EQ(home, spec.mount.paper_origin_D);
  for (double x : {-0.04, 0.0, 0.03}) {
    for (double y : {-0.025, 0.0, 0.025}) {
      const Vec2 p_D = deviceFromPaper(spec.mount, Vec2(x, y));
      Vec2 q;
      ASSERT_TRUE(fiveBarInverse(g, p_D, q)) << x << ", " << y;
      Vec2 back;
      ASSERT_TRUE(fiveBarForward(g, q, back));
      EXPECT_NEAR((back - p_D).norm(), 0.0, 1e-12);
      // The Jacobian against central differences.
      const Eigen::Matrix2d J = fiveBarJacobian(g, q);
      for (int j = 0; j < 2; ++j) {
        Vec2 dq = Vec2::Zero();
        dq[j] = 1e-7;
        Vec2 plus, minus;
        ASSERT_TRUE(fiveBarForward(g, q + dq, plus) && fiveBarForward(g, q - dq, minus));
        EXPECT_NEAR(((plus - minus) / 2e-7 - J.col(j)).norm(), 0.0, 1e-6);
      }
    }
  }
  Vec2 q;
  EXPECT_FALSE(fiveBarInverse(g, Vec2(0.0, 0.5), q));  // beyond the links' reach
}

TEST(PlanarPen, ForcesBecomeEffortsByTheJacobianTranspose) {
  PlanarPenSpec spec = referencePlanarPen();
  const Vec2 q = spec.home_q;
  // Virtual work: the joints' torques times a small joint motion equal the force times the
  // pen's motion.
  const Vec3 f_W(0.7, -0.4, 5.0);  // the normal part has nothing to act on
  const Vec2 torque = jointTorques(spec, q, f_W);
  const Vec2 dq(1e-6, -2e-6);
  Vec3 p0, p1;
  ASSERT_TRUE(penPosition(spec, q, p0) && penPosition(spec, q + dq, p1));
  EXPECT_NEAR(torque.dot(dq), f_W.head<2>().dot((p1 - p0).head<2>()), 1e-9);

  const auto efforts = motorEfforts(spec, torque);
  const Vec2 back = torquesForEfforts(spec, efforts[0], efforts[1]);
  EXPECT_NEAR((back - torque).norm(), 0.0, spec.peak_torque_Nm / HPEN_EFFORT_FULL);
  // A motor wired the other way round gets the opposite effort; past the peak, the effort clamps.
  spec.motor_sign = 1;
  EXPECT_EQ(motorEfforts(spec, torque)[0], -efforts[0]);
  EXPECT_EQ(motorEfforts(spec, Vec2(10.0, -10.0))[1], -HPEN_EFFORT_FULL);
}

TEST(PlanarPen, LimitsHoldEverywhereInTheWritingArea) {
  const PlanarPenSpec spec = referencePlanarPen();
  const DeviceLimits limits = planarPenLimits(spec);
  EXPECT_EQ(limits.degrees_of_freedom, 2);
  EXPECT_GT(limits.continuous_force_N, 1.0);
  EXPECT_LE(limits.continuous_force_N, limits.peak_force_N);
  // Everywhere in the area (on a 2.5 mm grid, finer than the limits' own), the continuous force
  // in any direction needs no more than the continuous torque at either joint.
  double worst_share = 0.0;
  for (double x = limits.workspace_min_m.x(); x <= limits.workspace_max_m.x() + 1e-9; x += 0.0025) {
    for (double y = limits.workspace_min_m.y(); y <= limits.workspace_max_m.y() + 1e-9; y += 0.0025) {
      Vec2 q;
      ASSERT_TRUE(fiveBarInverse(spec.geometry, deviceFromPaper(spec.mount, Vec2(x, y)), q));
      for (int k = 0; k < 72; ++k) {
        const double a = k * std::numbers::pi / 36.0;
        const Vec3 f = limits.continuous_force_N * Vec3(std::cos(a), std::sin(a), 0.0);
        worst_share = std::max(worst_share, jointTorques(spec, q, f).cwiseAbs().maxCoeff() / spec.continuous_torque_Nm);
      }
    }
  }
  EXPECT_LE(worst_share, 1.02) << "between the limits' 5 mm grid points the force may be a little weaker";
  EXPECT_GT(worst_share, 0.98) << "somewhere the limit is reached: it is not set lower than it need be";
  // A linkage too short for the area is refused, naming a point it cannot reach.
  PlanarPenSpec tiny = spec;
  tiny.geometry.distal_m = 0.05;
  EXPECT_THROW(planarPenLimits(tiny), InputError);
}

TEST(PlanarPen, TheHandPressesOnTheTableAndTheMotorsMoveThePen) {
  // A hand pressing 1 N at 60° holds the pen where it is; the sensor reads the normal share.
  StillHand hand(HandCommand{.press_N = 1.0, .pen_down = true});
  SimulatedPlanarDevice device({}, &hand);
  PenState pen;
  for (int i = 1; i <= 200; ++i) ASSERT_EQ(device.read(std::chrono::milliseconds(i), pen), DeviceStatus::kOk);
  EXPECT_NEAR(pen.pressure_raw, std::sin(std::numbers::pi / 3.0), 1e-6);
  EXPECT_EQ(pen.p_WT.z(), 0.0);
  EXPECT_LT(pen.p_WT.head<2>().norm(), 1e-4);
  // A force to the right moves the pen to the right against the hand's stiffness.
  for (int i = 201; i <= 1200; ++i) {
    ASSERT_EQ(device.write(Vec3(1.0, 0.0, 0.0)), DeviceStatus::kOk);
    ASSERT_EQ(device.read(std::chrono::milliseconds(i), pen), DeviceStatus::kOk);
  }
  EXPECT_GT(pen.p_WT.x(), 0.5 / 300.0);  // at least half what 1 N does on the hand's 300 N/m
  EXPECT_NEAR(pen.p_WT.y(), 0.0, 1e-3);
  // Without writes for the pen's watchdog time, the motors stop and the hand pulls it back.
  for (int i = 1201; i <= 2200; ++i) ASSERT_EQ(device.read(std::chrono::milliseconds(i), pen), DeviceStatus::kOk);
  EXPECT_LT(std::abs(pen.p_WT.x()), 2e-4);
}

}  // namespace
}  // namespace hattr::device
