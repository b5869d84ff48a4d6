// hattr's serial:// device against the open pen: the real firmware under the emulator, and a
// scripted pen on a pseudo-terminal for what the firmware never sends (corrupted STATEs).

#include <signal.h>
#include <stdlib.h>

#include <atomic>
#include <thread>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/device/serial_device.hpp"
#include "hattr/servo/servo_loop.hpp"
#include "integration/openpen_test_support.hpp"

namespace hattr::test {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;

/// A constant force on the pen.
class ConstantForce final : public GuidanceController {
 public:
  explicit ConstantForce(Vec3 f) : f_(f) {}
  Vec3 compute(const PenState&, const ContactForces&, double) noexcept override { return f_; }

 private:
  Vec3 f_;
};

TEST(OpenPenDevice, AProtocolVersionMismatchIsRefusedNamingBothVersions) {
  HATTR_SKIP_WITHOUT_OPEN_PEN();
  TempDir dir;
  PenEmulator emulator(dir, {"--hangups", "1", "--linger-ms", "0"}, penFirmwareV2());
  const std::string message = inputErrorOf([&] { device::openDevice("serial://" + emulator.pty() + "?timeout_s=5", nullptr); });
  EXPECT_THAT(message, HasSubstr("the pen speaks protocol version 2, this hattr speaks version 1"));
  EXPECT_EQ(emulator.process().wait(), 0);
}

TEST(OpenPenDevice, AnUnpluggedCableFaultsTheLoopWithin20msAtZeroForce) {
  HATTR_SKIP_WITHOUT_OPEN_PEN();
  TempDir dir;
  PenEmulator emulator(dir, {});
  device::SerialDevice pen(device::serialDeviceParams(device::parseDeviceUri("serial://" + emulator.pty() + "?lockstep=1")),
                           "serial://emulated");
  ConstantForce force(Vec3(0.5, 0.0, 0.0));
  servo::ServoLoop loop(pen, servo::ServoConfig{.rate_hz = 1000.0});
  loop.setGuidance(&force);
  loop.start();
  // Past the safety path's ramp: the force is on, then the cable goes (the emulator dies).
  std::vector<Sample> samples;
  TickSample s;
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  while ((samples.empty() || samples.back().t_s < 0.5) && std::chrono::steady_clock::now() < deadline) {
    while (loop.samples().tryPop(s)) samples.push_back(s.sample);
    std::this_thread::sleep_for(1ms);
  }
  ASSERT_GE(samples.back().t_s, 0.5) << "the loop did not run on the pen's clock";
  EXPECT_GT(samples.back().f_cmd_W.norm(), 0.05) << "the force is on (the free pen meets the soft walls)";
  emulator.process().signal(SIGKILL);
  while (loop.counters().link_faults.load() == 0 && std::chrono::steady_clock::now() < deadline) std::this_thread::sleep_for(1ms);
  std::this_thread::sleep_for(50ms);
  loop.stop();
  while (loop.samples().tryPop(s)) samples.push_back(s.sample);
  ASSERT_EQ(loop.counters().link_faults.load(), 1u);
  EXPECT_THAT(pen.faultReason(), HasSubstr("the port closed"));

  // The first sample without force comes within 20 ms (on the pen's clock) of the last one with it.
  std::size_t first_zero = 0;
  while (first_zero < samples.size() && samples[first_zero].t_s < 0.5) ++first_zero;
  while (first_zero < samples.size() && samples[first_zero].f_cmd_W.norm() > 0.0) ++first_zero;
  ASSERT_LT(first_zero, samples.size());
  EXPECT_LE(samples[first_zero].t_s - samples[first_zero - 1].t_s, 0.020);
  for (std::size_t i = first_zero; i < samples.size(); ++i) ASSERT_EQ(samples[i].f_cmd_W.norm(), 0.0) << "sample " << i;
}

TEST(OpenPenDevice, TheEmulatorInRealTimeKeepsToTheWallClock) {
  // A smoke check of the real-time mode: the firmware's clock follows the wall clock and the loop
  // runs on it. (On a loaded machine it falls behind, then catches up faster than the wall: so
  // the loop's time may run ahead of the wall time since START by that lag, bounded here.)
  HATTR_SKIP_WITHOUT_OPEN_PEN();
  TempDir dir;
  PenEmulator emulator(dir, {"--clock", "realtime"});
  device::SerialDevice pen(device::serialDeviceParams(device::parseDeviceUri("serial://" + emulator.pty() + "?state_timeout_s=1")),
                           "serial://emulated");
  servo::ServoLoop loop(pen, servo::ServoConfig{.rate_hz = 1000.0});
  const auto start = std::chrono::steady_clock::now();
  loop.start();
  std::this_thread::sleep_for(1s);
  Sample last;
  ASSERT_TRUE(loop.latest().read(last));
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  loop.stop();
  EXPECT_EQ(loop.counters().link_faults.load(), 0u) << pen.faultReason();
  EXPECT_GT(last.t_s, 0.3) << "the firmware's clock hardly ran";
  EXPECT_LE(last.t_s, wall_s + 0.05) << "simulated time ran ahead of the wall clock";
  EXPECT_EQ(pen.counters().malformed, 0u);
}

/// A pen played by the test on a pty's master: its IDENTITY, then STATEs as the test writes them.
class ScriptedPen {
 public:
  ScriptedPen() : master_(::posix_openpt(O_RDWR | O_NOCTTY)) {
    EXPECT_EQ(::grantpt(master_), 0);
    EXPECT_EQ(::unlockpt(master_), 0);
    slave_ = ::ptsname(master_);
    port_ = std::make_unique<ProtocolPort>(master_);
  }
  [[nodiscard]] const std::string& path() const { return slave_; }
  ProtocolPort& port() { return *port_; }

  /// Answers the HELLO with the reference build's identity.
  void answerHello() {
    for (auto f = port_->next(); f; f = port_->next()) {
      if (f->type != HPEN_HELLO) continue;
      hpen_hello hello{};
      hpen_decode_hello(f->payload.data(), &hello);
      hpen_identity id{};
      id.nonce = hello.nonce;
      std::memcpy(id.model, "scripted-pen", HPEN_MODEL_BYTES);
      const device::PlanarPenSpec ref = device::referencePlanarPen();
      id.state_rate_hz = 1000;
      id.watchdog_ms = 20;
      id.base_separation_m = static_cast<float>(ref.geometry.base_separation_m);
      id.proximal_m = static_cast<float>(ref.geometry.proximal_m);
      id.distal_m = static_cast<float>(ref.geometry.distal_m);
      id.home_q0_rad = static_cast<float>(ref.home_q[0]);
      id.home_q1_rad = static_cast<float>(ref.home_q[1]);
      id.counts_per_joint_rev = 20000;
      id.peak_torque_Nm = 0.693f;
      id.continuous_torque_Nm = 0.277f;
      id.sensor_N_per_count = 0.01f;
      id.sensor_zero_count = 100;
      id.sensor_max_count = 1023;
      std::uint8_t p[HPEN_IDENTITY_BYTES];
      hpen_encode_identity(p, &id);
      port_->send(HPEN_IDENTITY, p, HPEN_IDENTITY_BYTES);
      return;
    }
  }
  std::vector<std::uint8_t> state(std::uint16_t seq, bool send = true, std::uint8_t version = HPEN_PROTOCOL_VERSION) {
    hpen_state s{};
    s.seq = seq;
    s.time_us = seq * 1000u;
    s.sensor = 100;
    std::uint8_t p[HPEN_STATE_BYTES];
    hpen_encode_state(p, &s);
    std::uint8_t frame[HPEN_MAX_FRAME_BYTES];
    const std::uint8_t n = hpen_frame(frame, version, HPEN_STATE, p, HPEN_STATE_BYTES);
    std::vector<std::uint8_t> bytes(frame, frame + n);
    if (send) port_->sendBytes(bytes);
    return bytes;
  }

 private:
  int master_;
  std::string slave_;
  std::unique_ptr<ProtocolPort> port_;
};

TEST(OpenPenDevice, BadStatesAreDroppedAndCountedOnTheHost) {
  ScriptedPen scripted;
  std::thread answer([&] { scripted.answerHello(); });
  device::SerialDevice pen(device::serialDeviceParams(device::parseDeviceUri("serial://" + scripted.path() + "?state_timeout_s=5")),
                          "serial://scripted");
  answer.join();
  EXPECT_EQ(pen.spec().model, "scripted-pen");
  std::atomic<int> ticks{0};
  pen.startClock([](void* context, std::chrono::nanoseconds) noexcept { ++*static_cast<std::atomic<int>*>(context); }, &ticks);
  ASSERT_TRUE(scripted.port().next());  // START
  scripted.state(1);
  auto corrupted = scripted.state(2, false);
  corrupted[10] ^= 0x80;
  scripted.port().sendBytes(corrupted);
  scripted.state(3);
  scripted.state(3);  // again
  scripted.state(2);  // older
  scripted.state(4, true, HPEN_PROTOCOL_VERSION + 1);
  scripted.state(6);  // 4 (wrong version) and 5 never came
  const auto deadline = std::chrono::steady_clock::now() + 5s;
  while (pen.counters().states < 3 && std::chrono::steady_clock::now() < deadline) std::this_thread::sleep_for(1ms);
  pen.stopClock();
  const device::SerialCounters c = pen.counters();
  EXPECT_EQ(c.states, 3u);
  EXPECT_EQ(ticks.load(), 3);
  EXPECT_EQ(c.malformed, 1u);
  EXPECT_EQ(c.out_of_sequence, 2u);
  EXPECT_EQ(c.wrong_version, 1u);
  EXPECT_EQ(c.lost_states, 3u) << "2 (corrupted) then 4 and 5";
}

/// What the device said at each tick of its clock (the test's stand-in for the servo loop).
struct TickLog {
  device::SerialDevice* pen = nullptr;
  std::vector<std::pair<double, device::DeviceStatus>> ticks;
  static void tick(void* context, std::chrono::nanoseconds now) noexcept {
    auto* log = static_cast<TickLog*>(context);
    PenState state;
    log->ticks.emplace_back(std::chrono::duration<double>(now).count(), log->pen->read(now, state));
  }
};

TEST(OpenPenDevice, APenThatFallsSilentIsLostAfterItsWatchdogTime) {
  // No lockstep: the pen's 20 ms watchdog time is the host's limit too.
  ScriptedPen scripted;
  std::thread answer([&] { scripted.answerHello(); });
  device::SerialDevice pen(device::serialDeviceParams(device::parseDeviceUri("serial://" + scripted.path())), "serial://quiet");
  answer.join();
  TickLog log{.pen = &pen};
  pen.startClock(&TickLog::tick, &log);
  ASSERT_TRUE(scripted.port().next());  // START
  for (std::uint16_t seq = 1; seq <= 5; ++seq) scripted.state(seq);
  std::this_thread::sleep_for(200ms);
  pen.stopClock();
  ASSERT_GE(log.ticks.size(), 6u);
  std::size_t lost = 0;
  while (lost < log.ticks.size() && log.ticks[lost].second == device::DeviceStatus::kOk) ++lost;
  ASSERT_EQ(lost, 5u) << "five STATEs, five good ticks";
  ASSERT_LT(lost, log.ticks.size());
  EXPECT_EQ(log.ticks[lost].second, device::DeviceStatus::kDisconnected);
  const double silence_s = log.ticks[lost].first - log.ticks[lost - 1].first;
  EXPECT_GE(silence_s, 0.020);
  EXPECT_LT(silence_s, 0.100) << "the link is declared lost soon after the watchdog time";
  EXPECT_THAT(pen.faultReason(), HasSubstr("no STATE from the pen for 20 ms"));
  for (std::size_t i = lost; i < log.ticks.size(); ++i) EXPECT_EQ(log.ticks[i].second, device::DeviceStatus::kDisconnected);
}

TEST(OpenPenDevice, HomeNeverOnAPenNotYetHomedIsRefused) {
  ScriptedPen scripted;
  std::thread answer([&] { scripted.answerHello(); });
  const std::string message = inputErrorOf(
      [&] { device::openDevice("serial://" + scripted.path() + "?home=never", nullptr); });
  answer.join();
  EXPECT_THAT(message, HasSubstr("has not been homed since it was powered up"));
}

}  // namespace
}  // namespace hattr::test
