#include "hattr/servo/servo_loop.hpp"

#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "hattr/device/simulated_device.hpp"
#include "hattr/render/flat_paper.hpp"
#include "support/no_allocation.hpp"

namespace hattr::servo {
namespace {

using namespace std::chrono_literals;

/// A guidance stage returning whatever force the test sets.
class FixedGuidance final : public GuidanceController {
 public:
  Vec3 force = Vec3::Zero();
  Vec3 compute(const PenState&, const ContactForces&, double) noexcept override { return force; }
  bool setParameter(int parameter, double value) noexcept override {
    if (parameter != 0) return false;
    force.x() = value;
    return true;
  }
};

/// The simulated pen writing circles on flat paper: the full pipeline of this issue.
struct Rig {
  explicit Rig(ServoConfig config = {}, std::size_t ring = 1u << 16)
      : hand(Vec3(0.0, 0.0, 0.0), 0.015, 1.0, 1.0),
        device(device::SimulatedPenParams{}, &hand),
        loop(device, withRing(config, ring)) {
    loop.setWorld(&paper);
    loop.setGuidance(&guidance);
  }
  static ServoConfig withRing(ServoConfig config, std::size_t ring) {
    config.sample_ring_capacity = ring;
    return config;
  }
  std::vector<Sample> drain() {
    std::vector<Sample> out;
    TickSample s;
    while (loop.samples().tryPop(s)) out.push_back(s.sample);
    return out;
  }
  device::CircleHand hand;
  device::SimulatedDevice device;
  render::FlatPaper paper;
  FixedGuidance guidance;
  ServoLoop loop;
};

TEST(ServoLoop, TickNeverAllocatesNorLocks) {
  Rig rig;
  rig.guidance.force = Vec3(0.1, 0.0, 0.0);
  rig.loop.runSimulated(10);  // warm up outside the scope
  const test::NoAllocationScope scope;
  for (int i = 0; i < 10'000; ++i) {
    (void)rig.loop.tick(rig.loop.simulatedNow() + i * rig.loop.period());
  }
  EXPECT_EQ(scope.allocations(), 0u);
  if (test::lockHookActive()) {
    EXPECT_EQ(scope.locks(), 0u);
  }
}

TEST(ServoLoop, NoAllocationScopeCatchesAnAllocationAndALock) {
  // The guard itself must be able to fail.
  const test::NoAllocationScope scope;
  auto* leak = new int(3);
  EXPECT_EQ(scope.allocations(), 1u);
  delete leak;
  std::mutex mutex;
  { const std::lock_guard lock(mutex); }
  if (test::lockHookActive()) {
    EXPECT_EQ(scope.locks(), 1u);
  }
}

TEST(ServoLoop, SimulatedRunsAreBitForBitRepeatable) {
  const auto run = [] {
    Rig rig;
    rig.loop.runSimulated(5000);
    return rig.drain();
  };
  const std::vector<Sample> a = run();
  const std::vector<Sample> b = run();
  ASSERT_EQ(a.size(), 5000u);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(std::memcmp(&a[i], &b[i], sizeof(Sample)), 0) << "sample " << i;
  }
  // And the pen really wrote: it touched the paper and moved.
  EXPECT_TRUE(a.back().in_contact);
  EXPECT_GT((a.back().p_WT - a.front().p_WT).norm(), 0.005);
}

// In simulated time the newest sample for a display is written once a call, on its last tick:
// between calls it is the sample of the last tick run, and a read sees it once.
TEST(ServoLoop, SimulatedRunsLeaveTheLastTicksSampleForTheDisplay) {
  const auto expectSame = [](const Sample& a, const Sample& b) {  // field by field: Sample has padding
    EXPECT_EQ(a.t_s, b.t_s);
    EXPECT_EQ(a.p_WT, b.p_WT);
    EXPECT_EQ(a.v_WT, b.v_WT);
    EXPECT_EQ(a.f_user_W, b.f_user_W);
    EXPECT_EQ(a.f_cmd_W, b.f_cmd_W);
    EXPECT_EQ(a.in_contact, b.in_contact);
  };
  Rig rig;
  rig.loop.runSimulated(100);
  const std::vector<Sample> ring = rig.drain();
  ASSERT_EQ(ring.size(), 100u);
  EXPECT_EQ(rig.loop.counters().ticks.load(), 100u);
  Sample latest;
  ASSERT_TRUE(rig.loop.latest().read(latest));
  expectSame(latest, ring.back());
  EXPECT_NE(latest.t_s, ring[98].t_s);
  EXPECT_FALSE(rig.loop.latest().read(latest));  // nothing newer
  rig.loop.runSimulated(1);
  ASSERT_TRUE(rig.loop.latest().read(latest));
  expectSame(latest, rig.drain().back());
  EXPECT_EQ(rig.loop.counters().ticks.load(), 101u);
}

TEST(ServoLoop, NanForceLatchesAFaultAndTheDeviceGetsZero) {
  Rig rig;
  rig.loop.runSimulated(500);
  rig.guidance.force = Vec3(std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0);
  EXPECT_EQ(rig.loop.tick(rig.loop.simulatedNow()), TickStatus::kFaulted);
  EXPECT_EQ(rig.device.lastCommand(), Vec3::Zero());
  // Latched: a good force afterwards still gives zero until the fault is cleared.
  rig.guidance.force = Vec3(0.3, 0.0, 0.0);
  rig.loop.runSimulated(100);
  EXPECT_EQ(rig.device.lastCommand(), Vec3::Zero());
  EXPECT_EQ(rig.loop.counters().faults.load(), 1u);
  ASSERT_TRUE(rig.loop.post({ServoCommand::Type::kClearFault}));
  rig.loop.runSimulated(400);
  EXPECT_NE(rig.device.lastCommand(), Vec3::Zero());
}

TEST(ServoLoop, AFaultIsPublishedOnlyAfterItsTickIsCounted) {
  // A trial's watcher that sees the fault counter move reads the tick counter next and ends
  // the recording there: the faulting tick (its sample, with zero command) must already be
  // counted, or the recording loses it. Every even tick faults and every odd one clears the
  // fault; a watcher spinning on another core checks, at every count it sees, that the tick
  // of that fault is counted (fault k is tick 2(k - 1)).
  constexpr std::uint64_t kTicks = 60'000;
  Rig rig({}, 64);
  const Vec3 nan_force(std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0);
  std::atomic<bool> done{false};
  std::thread ticker([&] {
    for (std::uint64_t i = 0; i < kTicks; i += 2) {
      rig.guidance.force = nan_force;
      (void)rig.loop.tick(rig.loop.simulatedNow() + static_cast<std::int64_t>(i) * rig.loop.period());
      rig.guidance.force = Vec3::Zero();
      while (!rig.loop.post({ServoCommand::Type::kClearFault})) {
      }
      (void)rig.loop.tick(rig.loop.simulatedNow() + static_cast<std::int64_t>(i + 1) * rig.loop.period());
      TickSample drained;
      while (rig.loop.samples().tryPop(drained)) {
      }
    }
    done.store(true);
  });
  std::uint64_t checked = 0;
  std::uint64_t early = 0;
  std::uint64_t last_seen = 0;
  while (!done.load()) {
    const std::uint64_t faults = rig.loop.counters().faults.load();
    if (faults == last_seen) continue;
    last_seen = faults;
    const std::uint64_t ticks = rig.loop.counters().ticks.load();
    ++checked;
    if (ticks < 2 * faults - 1) ++early;
  }
  ticker.join();
  EXPECT_EQ(rig.loop.counters().faults.load(), kTicks / 2);
  EXPECT_GT(checked, 0u);
  EXPECT_EQ(early, 0u) << "a fault was visible before its tick was counted, " << early << " times of " << checked;
}

/// The simulated pen, whose reads fail (as a vendor SDK's do: the state is left unfilled)
/// from read `fail_from` on.
class FailingReads final : public device::Device {
 public:
  FailingReads(device::Device& inner, std::uint64_t fail_from) : inner_(inner), fail_from_(fail_from) {}
  device::DeviceStatus read(std::chrono::nanoseconds now, PenState& out) noexcept override {
    if (reads_++ >= fail_from_) return device::DeviceStatus::kFault;
    return inner_.read(now, out);
  }
  device::DeviceStatus write(const Vec3& f) noexcept override { return inner_.write(f); }
  const device::DeviceLimits& limits() const noexcept override { return inner_.limits(); }
  device::DeviceCapabilities capabilities() const noexcept override { return inner_.capabilities(); }
  const std::string& uri() const noexcept override { return inner_.uri(); }

 private:
  device::Device& inner_;
  std::uint64_t fail_from_;
  std::uint64_t reads_ = 0;
};

TEST(ServoLoop, AFailedReadHoldsTheLastGoodPenAtTheTicksTime) {
  // The faulting tick's sample is the one a recording ends with: it must carry the tick's
  // time (not a default 0, which a loop-time window drops) and the last position read, at rest.
  Rig rig;
  FailingReads failing(rig.device, 300);
  ServoLoop loop(failing, ServoConfig{});
  loop.setWorld(&rig.paper);
  loop.setGuidance(&rig.guidance);
  rig.guidance.force = Vec3(0.3, 0.0, 0.0);
  loop.runSimulated(302);
  std::vector<Sample> samples;
  TickSample item;
  while (loop.samples().tryPop(item)) samples.push_back(item.sample);
  ASSERT_EQ(samples.size(), 302u);
  const Sample& good = samples[299];
  EXPECT_GT(good.f_cmd_W.norm(), 0.0);
  for (std::size_t i : {300u, 301u}) {
    EXPECT_NEAR(samples[i].t_s, static_cast<double>(i) * 1e-3, 1e-12) << "tick " << i;
    EXPECT_EQ(samples[i].p_WT, good.p_WT) << "tick " << i;
    EXPECT_EQ(samples[i].v_WT, Vec3::Zero()) << "tick " << i;  // held at rest
    EXPECT_EQ(samples[i].f_cmd_W, Vec3::Zero()) << "tick " << i;
  }
  EXPECT_EQ(loop.counters().faults.load(), 1u);
}

TEST(ServoLoop, ForceAboveTheLimitIsClamped) {
  Rig rig;
  rig.guidance.force = Vec3(50.0, 0.0, 0.0);
  rig.loop.runSimulated(1000);
  const double limit = rig.device.limits().continuous_force_N;
  EXPECT_NEAR(rig.device.lastCommand().norm(), limit, 1e-9);
  EXPECT_GT(rig.loop.safety().clampCount(), 0u);
}

TEST(ServoLoop, StalledLoopTripsTheWatchdogAndZeroesForce) {
  Rig rig;
  rig.guidance.force = Vec3(0.5, 0.0, 0.0);
  rig.loop.runSimulated(1000);
  ASSERT_GT(rig.device.lastCommand().norm(), 0.4);
  // 20 ms between ticks: beyond the 10 ms threshold.
  EXPECT_EQ(rig.loop.tick(rig.loop.simulatedNow() + 20ms), TickStatus::kStalled);
  EXPECT_EQ(rig.device.lastCommand(), Vec3::Zero());
  EXPECT_EQ(rig.loop.counters().stalls.load(), 1u);
}

TEST(ServoLoop, ForcesRampInAfterStart) {
  ServoConfig config;
  config.safety.ramp_time_s = 0.2;
  Rig rig(config);
  // A hand holding the pen still above the paper: only the guidance force acts.
  device::StillHand still(device::HandCommand{.p_target_W = rig.device.params().start_position_W});
  rig.device.setHand(&still);
  rig.guidance.force = Vec3(1.0, 0.0, 0.0);
  std::vector<double> commanded;
  for (int i = 0; i < 300; ++i) {
    rig.loop.runSimulated(1);
    commanded.push_back(rig.device.lastCommand().x());
  }
  EXPECT_NEAR(commanded[0], 1.0 * 0.001 / 0.2, 1e-12);  // 1/200 of the force on the first tick
  EXPECT_NEAR(commanded[99], 0.5, 1e-9);                // half way at 100 ms
  EXPECT_NEAR(commanded[299], 1.0, 1e-12);              // all of it after the ramp
  for (std::size_t i = 1; i < commanded.size(); ++i) EXPECT_GE(commanded[i], commanded[i - 1]);
}

TEST(ServoLoop, SlowConsumerMakesTheLoopCountDropsNotBlock) {
  Rig rig({}, 64);
  rig.loop.runSimulated(1000);  // nobody drains
  EXPECT_EQ(rig.loop.counters().ticks.load(), 1000u);
  EXPECT_EQ(rig.loop.counters().dropped_samples.load(), 1000u - 64u);
  EXPECT_EQ(rig.drain().size(), 64u);
}

TEST(ServoLoop, StoppedRequiredConsumerZeroesForce) {
  Rig rig;
  std::atomic<double> consumer_time{0.0};
  rig.loop.requireConsumer(&consumer_time);
  rig.guidance.force = Vec3(0.5, 0.0, 0.0);
  rig.loop.runSimulated(5);
  EXPECT_NE(rig.device.lastCommand(), Vec3::Zero());
  rig.loop.runSimulated(20);  // consumer still at t = 0: 25 ms behind
  EXPECT_EQ(rig.device.lastCommand(), Vec3::Zero());
  EXPECT_GT(rig.loop.counters().consumer_stalls.load(), 0u);
}

TEST(ServoLoop, MailboxForwardsGuidanceParameters) {
  Rig rig;
  ASSERT_TRUE(rig.loop.post({ServoCommand::Type::kSetGuidanceParameter, 0, 0.25}));
  rig.loop.runSimulated(1);
  EXPECT_EQ(rig.guidance.force.x(), 0.25);
}

/// Adds each parameter-0 value it is given, counting the calls.
class SummingGuidance final : public GuidanceController {
 public:
  double sum = 0.0;
  std::uint64_t calls = 0;
  Vec3 compute(const PenState&, const ContactForces&, double) noexcept override { return Vec3::Zero(); }
  bool setParameter(int parameter, double value) noexcept override {
    if (parameter != 0) return false;
    sum += value;
    ++calls;
    return true;
  }
};

// Two threads post at once (a GUI and a watchdog, say): every command arrives exactly once. The
// mailbox's ring has one producer; post() turns a second one away while the first pushes (it
// retries), where two unguarded producers would race on the ring's head and lose or repeat
// commands.
TEST(ServoLoop, TheMailboxTakesCommandsFromTwoThreadsLosingNoneRepeatingNone) {
  Rig rig;
  SummingGuidance summing;
  rig.loop.setGuidance(&summing);
  constexpr int kEach = 100'000;
  std::atomic<int> finished{0};
  const auto poster = [&](double value) {
    for (int i = 0; i < kEach; ++i) {
      while (!rig.loop.post({ServoCommand::Type::kSetGuidanceParameter, 0, value})) {
      }
    }
    finished.fetch_add(1);
  };
  std::thread a(poster, 1.0);
  std::thread b(poster, 1000.0);
  while (finished.load() < 2) {
    rig.loop.runSimulated(1);
    (void)rig.drain();
  }
  a.join();
  b.join();
  rig.loop.runSimulated(16);  // what the last posts left in the mailbox (64 at most, 8 a tick)
  EXPECT_EQ(summing.calls, 2u * kEach);
  EXPECT_EQ(summing.sum, kEach * 1.0 + kEach * 1000.0);
}

TEST(ServoLoop, RejectsRatesOutsideOneToTenKilohertz) {
  device::SimulatedDevice device(device::SimulatedPenParams{}, nullptr);
  EXPECT_THROW(ServoLoop(device, ServoConfig{.rate_hz = 20'000.0}), InputError);
  EXPECT_THROW(ServoLoop(device, ServoConfig{.rate_hz = 0.5}), InputError);
}

TEST(ServoLoop, RealTimeThreadTicksAndStops) {
  ServoConfig config;
  config.realtime.policy = RealtimePolicy::kSkip;
  Rig rig(config);
  rig.loop.start();
  // Wait for ticks rather than for time: a loaded host may hold the thread up for a while.
  const auto give_up = std::chrono::steady_clock::now() + 20s;
  while (rig.loop.counters().ticks.load() <= 10u && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(10ms);
  }
  rig.loop.stop();
  EXPECT_FALSE(rig.loop.running());
  EXPECT_GT(rig.loop.counters().ticks.load(), 10u);
  EXPECT_EQ(rig.loop.tickCompute().count(), rig.loop.counters().ticks.load());
  EXPECT_EQ(rig.device.lastCommand(), Vec3::Zero());  // zero force after stop
}

}  // namespace
}  // namespace hattr::servo
