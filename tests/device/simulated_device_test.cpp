#include "hattr/device/simulated_device.hpp"

#include <cmath>
#include <iostream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/device/device_uri.hpp"

namespace hattr::device {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;

PenState readAt(SimulatedDevice& device, double t_s) {
  PenState pen;
  EXPECT_EQ(device.read(std::chrono::nanoseconds(std::llround(t_s * 1e9)), pen), DeviceStatus::kOk);
  return pen;
}

TEST(SimulatedDevice, PenHeldStillWithNoForceStaysPut) {
  SimulatedPenParams params;
  params.start_position_W = Vec3(0.01, 0.02, 0.005);
  StillHand hand(HandCommand{.p_target_W = params.start_position_W});
  SimulatedDevice device(params, &hand);
  for (int i = 1; i <= 5000; ++i) {
    (void)readAt(device, i * 1e-3);
    ASSERT_EQ(device.write(Vec3::Zero()), DeviceStatus::kOk);
  }
  EXPECT_EQ(device.truePosition(), params.start_position_W);
  EXPECT_EQ(device.trueVelocity(), Vec3::Zero());
}

// A hand pushing 100 N down (nothing under the pen) drives it into the mechanism's end stop:
// it comes to rest just past the workspace's floor, where the stop's spring holds the push
// (100 N / 20 kN/m = 5 mm), not 100 mm or a metre below it (issue 38).
TEST(SimulatedDevice, EndStopsHoldThePenAtItsWorkspace) {
  SimulatedPenParams params;
  // A hand stronger than a person's that follows the pen all the way down (the default eases off).
  params.hand.max_force_N = 1000.0;
  params.hand.press_ease_begin_m = 1.0;
  params.hand.press_ease_end_m = 2.0;
  StillHand hand({.p_target_W = Vec3(0.0, 0.0, 0.0), .press_N = 100.0, .altitude_rad = 1.5707963267948966,
                  .pen_down = true});
  SimulatedDevice device(params, &hand);
  double deepest = 0.0;
  for (int i = 1; i <= 2000; ++i) {
    ASSERT_EQ(device.write(Vec3::Zero()), DeviceStatus::kOk);
    (void)readAt(device, i * 1e-3);
    deepest = std::min(deepest, device.truePosition().z());
  }
  const double floor = params.limits.workspace_min_m.z();
  const double held = floor - 100.0 / params.end_stop_stiffness_N_per_m;
  EXPECT_NEAR(device.truePosition().z(), held, 1e-4);
  EXPECT_LT(std::abs(device.trueVelocity().z()), 1e-3);
  EXPECT_GT(deepest, held - 0.002) << "the stop's damper keeps the overshoot small";
}

// A script asking the hand to press 100 N into a paper that is not there: the hand pushes with
// at most its grip's force, and as the pen sinks under the writing plane it eases off, so the
// pen comes to rest where the fingers' reach ends, far above the mechanism's end stop.
TEST(SimulatedDevice, TheHandPushesNoHarderThanAGripAndEasesOffUnderTheDesk) {
  SimulatedPenParams params;
  StillHand hand({.p_target_W = Vec3(0.0, 0.0, 0.0), .press_N = 100.0, .altitude_rad = 1.5707963267948966,
                  .pen_down = true});
  SimulatedDevice device(params, &hand);
  double strongest_N = 0.0;
  double deepest = 0.0;
  for (int i = 1; i <= 3000; ++i) {
    ASSERT_EQ(device.write(Vec3::Zero()), DeviceStatus::kOk);
    (void)readAt(device, i * 1e-3);
    strongest_N = std::max(strongest_N, device.lastHandForce().norm());
    deepest = std::min(deepest, device.truePosition().z());
  }
  EXPECT_LE(strongest_N, params.hand.max_force_N * (1.0 + 1e-12));
  EXPECT_NEAR(device.truePosition().z(), -params.hand.press_ease_end_m, 1e-4);
  EXPECT_GT(deepest, params.limits.workspace_min_m.z()) << "the fall never reached the mechanism's end stop";
  // The massless hand's overshoot past its reach, as docs/realtime.md states it (24.8 mm).
  EXPECT_NEAR(-deepest, 0.0248, 0.0005) << "docs/realtime.md's figure";
  std::cout << "[ info ] deepest " << deepest * 1e3 << " mm, strongest push " << strongest_N << " N\n";
}

// The press eases off linearly over the fingers' reach, the fingers hold the pen back past it,
// and a far target pulls with the cap.
TEST(SimulatedDevice, HandForceEasesLinearlyUnderTheWritingPlaneAndIsCapped) {
  HandImpedance hand;
  hand.damping_N_s_per_m = 0.0;
  const HandCommand press{.press_N = 10.0, .altitude_rad = 1.5707963267948966, .pen_down = true};
  const double mid = 0.5 * (hand.press_ease_begin_m + hand.press_ease_end_m);
  const auto down = [&](double depth) { return -handForce(hand, press, Vec3(0, 0, -depth), Vec3::Zero()).z(); };
  EXPECT_NEAR(down(0.001), 10.0, 1e-12);
  EXPECT_NEAR(down(hand.press_ease_begin_m), 10.0, 1e-12);
  EXPECT_NEAR(down(mid), 5.0, 1e-9);
  EXPECT_NEAR(down(hand.press_ease_end_m), 0.0, 1e-12);
  // Past the reach the fingers hold the pen back with the hand's stiffness.
  EXPECT_NEAR(down(hand.press_ease_end_m + 0.01), -0.01 * hand.stiffness_N_per_m, 1e-9);
  const HandCommand far{.p_target_W = Vec3(1.0, 0.0, 0.0)};  // 300 N/m x 1 m
  EXPECT_NEAR(handForce(hand, far, Vec3::Zero(), Vec3::Zero()).norm(), hand.max_force_N, 1e-9);
}

TEST(SimulatedDevice, ConstantForceAcceleratesAsTheMassDamperModelSays) {
  SimulatedPenParams params;
  params.start_position_W = Vec3::Zero();
  params.max_substep_s = 1e-5;
  // Free flight: the pen travels 91 mm, past the default workspace's end stops.
  params.limits.workspace_min_m = Vec3::Constant(-1.0);
  params.limits.workspace_max_m = Vec3::Constant(1.0);
  SimulatedDevice device(params, nullptr);
  const Vec3 force(0.2, -0.1, 0.05);
  const double m = params.mass_kg;
  const double b = params.damping_N_s_per_m;
  double t = 0.0;
  for (int i = 1; i <= 500; ++i) {
    t = i * 1e-3;
    ASSERT_EQ(device.write(force), DeviceStatus::kOk);
    (void)readAt(device, t);
  }
  // Exact solution of m·v' = F − b·v from rest.
  const double decay = std::exp(-b * t / m);
  const Vec3 v_exact = force / b * (1.0 - decay);
  const Vec3 p_exact = force / b * (t - m / b * (1.0 - decay));
  EXPECT_LT((device.trueVelocity() - v_exact).norm(), 1e-3 * v_exact.norm());
  EXPECT_LT((device.truePosition() - p_exact).norm(), 1e-3 * p_exact.norm());
}

TEST(SimulatedDevice, ForceDropsToZeroWhenCommandsStop) {
  SimulatedPenParams params;
  params.start_position_W = Vec3::Zero();
  params.damping_N_s_per_m = 0.0;
  SimulatedDevice device(params, nullptr);
  (void)readAt(device, 0.0);
  ASSERT_EQ(device.write(Vec3(1.0, 0.0, 0.0)), DeviceStatus::kOk);
  (void)readAt(device, 0.050);  // no write for 50 ms: force held only for the 10 ms timeout
  const double v_expected = 1.0 / params.mass_kg * params.command_timeout_s;
  EXPECT_NEAR(device.trueVelocity().x(), v_expected, 0.03 * v_expected);
}

TEST(SimulatedDevice, QuantizesReportedPositionsNotTheTrueOnes) {
  SimulatedPenParams params;
  params.position_quantum_m = 1e-4;
  params.start_position_W = Vec3(0.01234, -0.00051, 0.00049);
  SimulatedDevice device(params, nullptr);
  const PenState pen = readAt(device, 0.0);
  EXPECT_NEAR(pen.p_WT.x(), 0.0123, 1e-12);
  EXPECT_NEAR(pen.p_WT.y(), -0.0005, 1e-12);
  EXPECT_NEAR(pen.p_WT.z(), 0.0005, 1e-12);
  EXPECT_EQ(device.truePosition(), params.start_position_W);
}

TEST(SimulatedDevice, NonFiniteCommandIsAFaultAndZeroForce) {
  SimulatedDevice device(SimulatedPenParams{}, nullptr);
  EXPECT_EQ(device.write(Vec3(std::nan(""), 0, 0)), DeviceStatus::kFault);
  EXPECT_EQ(device.lastCommand(), Vec3::Zero());
}

TEST(Hand, PressesWithTheNormalShareOfItsAxialForce) {
  const HandCommand cmd{.press_N = 2.0, .altitude_rad = std::asin(0.75), .pen_down = true};
  const Vec3 f = handForce(HandImpedance{}, cmd, Vec3::Zero(), Vec3::Zero());
  EXPECT_NEAR(f.z(), -1.5, 1e-12);
  HandCommand lifted = cmd;
  lifted.pen_down = false;
  lifted.p_target_W = Vec3(0, 0, 0.01);
  EXPECT_NEAR(handForce(HandImpedance{.stiffness_N_per_m = 300}, lifted, Vec3::Zero(), Vec3::Zero()).z(), 3.0, 1e-12);
}

TEST(Hand, ProfileScriptInterpolatesAndReproducesTheNormalForce) {
  HapticProfile profile;
  for (int i = 0; i < 3; ++i) {
    Sample s;
    s.t_s = 10.0 + i * 0.01;
    s.p_WT = Vec3(i * 0.001, 0.0, 0.0);
    s.f_user_W = Vec3(0.0, 0.0, -1.0 - i);
    s.pen_down = true;
    profile.append(s);
  }
  ProfileHandScript script(profile, std::asin(0.5));
  const HandCommand mid = script.command(0.005);
  EXPECT_NEAR(mid.p_target_W.x(), 0.0005, 1e-12);
  EXPECT_NEAR(mid.press_N * 0.5, 1.5, 1e-12);  // axial · sin θ = recorded normal force
  EXPECT_NEAR(script.command(1.0).p_target_W.x(), 0.002, 1e-12);  // holds the end
}

// ---- URIs --------------------------------------------------------------------------------

std::string openError(const std::string& uri) {
  try {
    (void)openDevice(uri, nullptr);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(DeviceUri, OpensASimulatedPenWithParameters) {
  const auto device = openDevice("sim://pen?mass_kg=0.1&continuous_force_N=2.5", nullptr);
  auto* sim = dynamic_cast<SimulatedDevice*>(device.get());
  ASSERT_NE(sim, nullptr);
  EXPECT_EQ(sim->params().mass_kg, 0.1);
  EXPECT_EQ(device->limits().continuous_force_N, 2.5);
  EXPECT_EQ(device->limits().mass_kg, 0.1);
  EXPECT_EQ(device->uri(), "sim://pen?mass_kg=0.1&continuous_force_N=2.5");
}

TEST(DeviceUri, BadUrisListWhatIsAccepted) {
  EXPECT_THAT(openError("pen"), HasSubstr("expected scheme://target, accepted: sim://pen"));
  EXPECT_THAT(openError("usb://phantom"), HasSubstr("unknown scheme \"usb\"; accepted: sim://pen"));
  EXPECT_THAT(openError("usb://phantom"), HasSubstr("plugin:/path/libX.so[?key=value&...] or plugin:NAME"));
  EXPECT_THAT(openError("usb://phantom"), HasSubstr("udp://HOST:PORT?key=FILE"));
  EXPECT_THAT(openError("udp://10.0.0.1:5000"), HasSubstr("missing key=FILE"));
  EXPECT_THAT(openError("plugin:/opt/lib.so"), HasSubstr("plugin:/opt/lib.so: file not found"));
  EXPECT_THAT(openError("sim://pen?mass_kg=%2"), HasSubstr("expected %XX (two hex digits)"));
  EXPECT_THAT(openError("sim://arm"), HasSubstr("the simulator offers sim://pen and sim://planar, got sim://arm"));
  EXPECT_THAT(openError("sim://pen?mas_kg=1"), HasSubstr("unknown key \"mas_kg\": expected one of mass_kg"));
  EXPECT_EQ(openError("sim://pen?mass_kg=-1"), "sim://pen: key mass_kg: expected a number in [0.001, 10], got \"-1\"");
  EXPECT_THAT(openError("sim://pen?mass_kg"), HasSubstr("expected key=value in the query, got \"mass_kg\""));
  EXPECT_THAT(openError("sim://pen?continuous_force_N=9&peak_force_N=8"),
              HasSubstr("continuous_force_N (9) must not exceed peak_force_N (8)"));
  EXPECT_THAT(openError("sim://pen?hand_ease_begin_m=0.02"),
              HasSubstr("hand_ease_end_m (0.012) must lie beyond hand_ease_begin_m (0.02)"));
}

}  // namespace
}  // namespace hattr::device
