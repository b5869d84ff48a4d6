// Driver plugins through the real loader (dlopen): loading failures, the sim plugin against
// sim://pen, device-clocked loops, the replay plugin, and the vendor adapter with a fake vendor.

#include <dlfcn.h>
#include <signal.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <cmath>
#include <thread>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/device/device_uri.hpp"
#include "hattr/device/plugin_device.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/servo/servo_loop.hpp"
#include "hattr/session/study_runner.hpp"
#include "hattr/session/trial.hpp"
#include "support/host_stalls.hpp"
#include "support/no_allocation.hpp"
#include "support/test_support.hpp"
#include "support/thread_sanitizer.hpp"

namespace hattr::device {
namespace {

using namespace std::chrono_literals;

std::string uriOf(const char* path, const std::string& query = "") {
  return "plugin:" + std::string(path) + (query.empty() ? "" : "?" + query);
}

/// The message of the InputError that opening `uri` throws ("" if none).
std::string openError(const std::string& uri) {
  try {
    (void)openDevice(uri, nullptr);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(PluginLoading, MissingFileIsRefusedNamingThePath) {
  const std::string message = openError("plugin:/nonexistent/libnothing.so");
  EXPECT_NE(message.find("/nonexistent/libnothing.so: file not found"), std::string::npos) << message;
}

TEST(PluginLoading, FileThatIsNotASharedObjectIsRefused) {
  const test::TempDir dir;
  test::writeText(dir / "libfake.so", "this is text, not ELF\n");
  const std::string message = openError(uriOf((dir / "libfake.so").c_str()));
  EXPECT_NE(message.find("not a loadable shared object"), std::string::npos) << message;
}

TEST(PluginLoading, SharedObjectWithoutTheEntrySymbolIsRefused) {
  const std::string message = openError(uriOf(test::builtFile("HATTR_NO_ENTRY_PLUGIN")));
  EXPECT_NE(message.find("no entry symbol \"hattr_plugin_entry\": not a hattr driver plugin"), std::string::npos)
      << message;
}

TEST(PluginLoading, AbiVersionMismatchNamesBothVersions) {
  const std::string message = openError(uriOf(test::builtFile("HATTR_ABI_MISMATCH_PLUGIN")));
  EXPECT_NE(message.find("plugin ABI mismatch: the plugin speaks version 99, this hattr speaks version 1"),
            std::string::npos)
      << message;
}

TEST(PluginLoading, FailedOpenCarriesThePluginsOwnMessage) {
  const std::string message = openError(uriOf(test::builtFile("HATTR_FAKE_VENDOR_PLUGIN"), "fail_open=no%20device%20on%20USB"));
  EXPECT_NE(message.find("the plugin could not open the device: fake SDK: no device on USB"), std::string::npos)
      << message;
}

TEST(PluginLoading, UnknownKeyIsRefusedListingTheAcceptedOnes) {
  const std::string message = openError(uriOf(test::builtFile("HATTR_FAKE_VENDOR_PLUGIN"), "colour=red"));
  EXPECT_NE(message.find("unknown key \"colour\": expected one of max_force_N, paper_origin, clock"), std::string::npos)
      << message;
}

TEST(PluginLoading, ReplayAndSimPluginsRefuseUnknownKeysNamingTheirOwn) {
  EXPECT_NE(openError(uriOf(test::builtFile("HATTR_REPLAY_PLUGIN"), "force=x.csv")).find("unknown key \"force\": expected one of profile, forces"),
            std::string::npos);
  EXPECT_NE(openError(uriOf(test::builtFile("HATTR_SIM_PLUGIN"), "colour=red")).find("keys: clock, rate_hz and those of sim://pen"),
            std::string::npos);
}

TEST(PluginLoading, InspectReadsNameAndDescriptionWithoutOpening) {
  const PluginInfo info = inspectPlugin(test::builtFile("HATTR_SIM_PLUGIN"));
  EXPECT_EQ(info.name, "sim");
  EXPECT_EQ(info.abi_version, 1u);
  EXPECT_NE(info.description.find("simulated pen"), std::string::npos);
}

// ---- The sim plugin ---------------------------------------------------------------------

session::TrialResult runCircleTrial(const std::string& device_uri, guidance::TrainingMode mode,
                                    std::shared_ptr<const guidance::ReferenceTrajectory> reference) {
  session::TrialEnvironment env(device_uri, render::WorldConfig{}, 1000.0);
  CircleHand hand(Vec3(0.0, 0.0, 0.0), 0.012, 0.8, 1.0);
  session::TrialSetup setup{.duration_s = 1.0};
  setup.guidance.mode = mode;
  setup.reference = std::move(reference);
  return session::runTrial(env, setup, hand);
}

TEST(SimPlugin, TrialThroughThePluginIsBitIdenticalToSimPen) {
  HATTR_STARTS_NO_THREAD();
  const auto direct = runCircleTrial("sim://pen?mass_kg=0.05", guidance::TrainingMode::kBasic, nullptr);
  const auto plugged = runCircleTrial(uriOf(test::builtFile("HATTR_SIM_PLUGIN"), "mass_kg=0.05"), guidance::TrainingMode::kBasic, nullptr);
  ASSERT_EQ(direct.profile.size(), plugged.profile.size());
  EXPECT_TRUE(direct.profile.samples() == plugged.profile.samples());
  EXPECT_GT(direct.profile.penDownCount(), 100u);  // the hand really wrote on the paper

  // With guidance toward a reference, too.
  const auto reference = std::make_shared<guidance::ReferenceTrajectory>(direct.profile, 1000.0);
  const auto guided = runCircleTrial("sim://pen", guidance::TrainingMode::kPositionControl, reference);
  const auto guided_plugged = runCircleTrial(uriOf(test::builtFile("HATTR_SIM_PLUGIN")), guidance::TrainingMode::kPositionControl, reference);
  EXPECT_TRUE(guided.profile.samples() == guided_plugged.profile.samples());
}

TEST(SimPlugin, TickThroughThePluginNeverAllocates) {
  CircleHand hand(Vec3::Zero(), 0.01, 1.0, 1.0);
  const auto device = openDevice(uriOf(test::builtFile("HATTR_SIM_PLUGIN")), &hand);
  servo::ServoLoop loop(*device, servo::ServoConfig{});
  loop.runSimulated(10);
  const test::NoAllocationScope scope;
  loop.runSimulated(5000);
  EXPECT_EQ(scope.allocations(), 0u);
}

TEST(SimPlugin, ADeviceClockAtAnotherRateThanTheLoopsIsRefused) {
  const auto device = openDevice(uriOf(test::builtFile("HATTR_SIM_PLUGIN"), "clock=device&rate_hz=500"), nullptr);
  servo::ServoLoop loop(*device, servo::ServoConfig{.rate_hz = 1000.0});
  try {
    loop.start();
    FAIL() << "started";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("the device's clock runs at 500 Hz, the servo loop was set up for 1000 Hz: use --rate 500"),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(loop.running());
}

TEST(SimPlugin, DeviceClockRunsTheLoopAtTheDevicesRate) {
  (void)test::passesUnlessTheHostStalls([&](std::uint64_t& stalls) {
    CircleHand hand(Vec3::Zero(), 0.01, 1.0, 1.0);
    const auto device = openDevice(uriOf(test::builtFile("HATTR_SIM_PLUGIN"), "clock=device&rate_hz=1000"), &hand);
    ASSERT_EQ(device->clocking(), DeviceClocking::kDeviceClock);
    servo::ServoLoop loop(*device, servo::ServoConfig{});
    // The device's clock drives the loop: 300 ticks come, never sooner than its 1 kHz allows,
    // and most of them 1 ms apart (a host that holds the device's thread up makes it catch up
    // in a burst: the watch beside the test counts that).
    const test::HostStallWatch watch(stalls);
    const auto started = std::chrono::steady_clock::now();
    loop.start();
    while (loop.counters().ticks.load() < 300 && std::chrono::steady_clock::now() - started < 10s) {
      std::this_thread::sleep_for(5ms);
    }
    loop.stop();
    const double elapsed_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started).count();
    stalls += loop.counters().stalls.load();
    EXPECT_EQ(loop.clock(), servo::LoopClock::kDevice);
    EXPECT_EQ(servo::loopClockName(loop.clock()), "device");
    const auto ticks = loop.counters().ticks.load();
    EXPECT_GE(ticks, 300u);
    EXPECT_LE(static_cast<double>(ticks), elapsed_ms + 2.0);
    EXPECT_EQ(loop.periodError().count(), ticks - 1);
    EXPECT_LT(loop.periodError().percentile_ns(0.5), 500'000);  // at 500 Hz it would be 1 ms
    // The pen followed the hand, which circles 10 mm from the origin: the loop really ran it.
    Sample last;
    ASSERT_TRUE(loop.latest().read(last));
    EXPECT_GT(last.p_WT.head<2>().norm(), 0.003);
    EXPECT_EQ(loop.counters().faults.load(), 0u);
  });
}

// ---- The replay plugin ------------------------------------------------------------------

HapticProfile straightStroke() {
  HapticProfile p;
  for (int i = 0; i <= 100; ++i) {
    Sample s;
    s.t_s = 0.01 * i;
    s.p_WT = Vec3(0.001 * i, 0.0, 0.0);
    s.v_WT = Vec3(0.1, 0.0, 0.0);
    s.f_user_W = Vec3(0.0, 0.0, -1.0);
    s.pen_down = i >= 10;
    p.append(s);
  }
  return p;
}

TEST(ReplayPlugin, MovesThePenAlongTheProfileAndKeepsTheForcesItWasSent) {
  const test::TempDir dir;
  io::writeProfileCsv(straightStroke(), dir / "stroke.csv");
  const std::string uri = uriOf(test::builtFile("HATTR_REPLAY_PLUGIN"), "profile=" + (dir / "stroke.csv").string() + "&forces=" +
                                                         (dir / "forces.csv").string());
  {
    const auto device = openDevice(uri, nullptr);
    PenState pen;
    for (int ms = 0; ms <= 500; ++ms) {
      ASSERT_EQ(device->read(std::chrono::milliseconds(ms), pen), DeviceStatus::kOk);
      ASSERT_EQ(device->write(Vec3(0.001 * ms, 0.0, 0.0)), DeviceStatus::kOk);
    }
    EXPECT_NEAR(pen.p_WT.x(), 0.05, 1e-12);
    EXPECT_EQ(pen.buttons, 1u);
    EXPECT_NEAR(pen.f_measured_W.z(), -1.0, 1e-12);
  }
  const HapticProfile kept = io::readProfileCsv(dir / "forces.csv");
  ASSERT_EQ(kept.size(), 501u);
  EXPECT_NEAR(kept[250].f_cmd_W.x(), 0.25, 1e-12);
  EXPECT_NEAR(kept[250].p_WT.x(), 0.025, 1e-12);

  // A second run may not replace the recording.
  const std::string message = openError(uri);
  EXPECT_NE(message.find("exists; choose another file"), std::string::npos) << message;
}

// ---- The vendor adapter, with the fake vendor --------------------------------------------

/// The fake vendor's last force in its own frame, through its test hook.
Vec3 fakeVendorForce() {
  void* lib = dlopen(test::builtFile("HATTR_FAKE_VENDOR_PLUGIN"), RTLD_NOW | RTLD_NOLOAD);
  EXPECT_NE(lib, nullptr);
  void* symbol = dlsym(lib, "fake_vendor_last_force_D");
  void (*hook)(double*) = nullptr;
  std::memcpy(&hook, &symbol, sizeof(hook));
  double f[3];
  hook(f);
  dlclose(lib);
  return {f[0], f[1], f[2]};
}

TEST(VendorAdapter, ConvertsMillimetresAndTheSdkFrameBothWays) {
  const auto device = openDevice(uriOf(test::builtFile("HATTR_FAKE_VENDOR_PLUGIN"), "clock=host&start_mm=10,-40,5"), nullptr);
  PenState pen;
  ASSERT_EQ(device->read(1ms, pen), DeviceStatus::kOk);
  // D: x right, y up, z toward the user; the paper's origin at y_D = -60 mm.
  EXPECT_NEAR(pen.p_WT.x(), 0.010, 1e-9);
  EXPECT_NEAR(pen.p_WT.y(), -0.005, 1e-9);
  EXPECT_NEAR(pen.p_WT.z(), 0.020, 1e-9);
  ASSERT_EQ(device->write(Vec3(0.1, 0.2, 0.3)), DeviceStatus::kOk);
  const Vec3 f_D = fakeVendorForce();
  EXPECT_NEAR(f_D.x(), 0.1, 1e-12);
  EXPECT_NEAR(f_D.y(), 0.3, 1e-12);   // up
  EXPECT_NEAR(f_D.z(), -0.2, 1e-12);  // away from the user
}

TEST(VendorAdapter, ReportsTheSdksLimitsInSiAndLowersThemOnRequest) {
  const auto device = openDevice(uriOf(test::builtFile("HATTR_FAKE_VENDOR_PLUGIN"), "clock=host"), nullptr);
  const DeviceLimits& l = device->limits();
  EXPECT_NEAR(l.max_stiffness_N_per_m, 1260.0, 1e-9);
  EXPECT_NEAR(l.workspace_min_m.x(), -0.08, 1e-12);
  EXPECT_NEAR(l.workspace_min_m.y(), -0.05, 1e-12);
  EXPECT_NEAR(l.workspace_min_m.z(), 0.0, 1e-12);
  EXPECT_NEAR(l.workspace_max_m.z(), 0.12, 1e-12);
  EXPECT_DOUBLE_EQ(l.peak_force_N, 3.3);
  EXPECT_DOUBLE_EQ(l.continuous_force_N, 0.88);

  const auto gentle = openDevice(uriOf(test::builtFile("HATTR_FAKE_VENDOR_PLUGIN"), "clock=host&max_force_N=0.5"), nullptr);
  EXPECT_DOUBLE_EQ(gentle->limits().peak_force_N, 0.5);
  EXPECT_DOUBLE_EQ(gentle->limits().continuous_force_N, 0.5);
  const std::string message = openError(uriOf(test::builtFile("HATTR_FAKE_VENDOR_PLUGIN"), "clock=host&max_force_N=5"));
  EXPECT_NE(message.find("max_force_N: expected (0, 3.3] N"), std::string::npos) << message;
}

TEST(VendorAdapter, ClampsTheForceToThePeakAsTheLastLineOfDefence) {
  const auto device = openDevice(uriOf(test::builtFile("HATTR_FAKE_VENDOR_PLUGIN"), "clock=host"), nullptr);
  ASSERT_EQ(device->write(Vec3(0.0, 0.0, 10.0)), DeviceStatus::kOk);
  EXPECT_NEAR(fakeVendorForce().norm(), 3.3, 1e-12);
  EXPECT_EQ(device->write(Vec3(std::nan(""), 0.0, 0.0)), DeviceStatus::kFault);
  EXPECT_EQ(fakeVendorForce().norm(), 0.0);
}

TEST(VendorAdapter, SdkErrorBecomesAFaultWithTheSdksText) {
  const auto device = openDevice(uriOf(test::builtFile("HATTR_FAKE_VENDOR_PLUGIN"), "clock=host&error_after=3"), nullptr);
  PenState pen;
  for (int i = 0; i < 3; ++i) ASSERT_EQ(device->read(std::chrono::milliseconds(i), pen), DeviceStatus::kOk);
  EXPECT_EQ(device->read(3ms, pen), DeviceStatus::kFault);
  const std::string reason = device->faultReason();
  EXPECT_NE(reason.find("fake SDK: amplifier fault (SDK error 513)"), std::string::npos) << reason;
}

/// A guidance stage that pushes with a constant force.
struct ConstantPush final : GuidanceController {
  Vec3 compute(const PenState&, const ContactForces&, double) noexcept override { return Vec3(0.0, 0.0, 0.02); }
};

TEST(VendorAdapter, DeviceClockedLoopRunsInsideTheSdksFramesAndStopsAtZeroForce) {
  (void)test::passesUnlessTheHostStalls([&](std::uint64_t& stalls) {
    const auto device = openDevice(uriOf(test::builtFile("HATTR_FAKE_VENDOR_PLUGIN"), "clock=device"), nullptr);
    servo::ServoLoop loop(*device, servo::ServoConfig{});
    ConstantPush push;
    loop.setGuidance(&push);
    loop.start();
    // Ramped in, in the SDK's frame (y up): the largest force seen (a stall of this machine's
    // scheduler restarts the ramp, so one instant could miss it).
    double largest_up = 0.0;
    for (int i = 0; i < 1000 && (i < 200 || largest_up < 0.02 - 1e-9); ++i) {
      std::this_thread::sleep_for(2ms);
      largest_up = std::max(largest_up, fakeVendorForce().y());
    }
    loop.stop();
    stalls = loop.counters().stalls.load();
    EXPECT_NEAR(largest_up, 0.02, 1e-9);
    EXPECT_EQ(fakeVendorForce().norm(), 0.0);  // the device, still open, holds no force after stop
    EXPECT_EQ(loop.clock(), servo::LoopClock::kDevice);
    EXPECT_GT(loop.counters().ticks.load(), 0u);
    EXPECT_EQ(loop.counters().faults.load(), 0u);
  });
}

TEST(VendorAdapter, NonFiniteReadingLatchesAFaultAndZeroForce) {
  const auto device = openDevice(uriOf(test::builtFile("HATTR_FAKE_VENDOR_PLUGIN"), "clock=device&nan_after=50"), nullptr);
  servo::ServoLoop loop(*device, servo::ServoConfig{});
  loop.start();
  std::this_thread::sleep_for(150ms);
  loop.stop();
  EXPECT_EQ(loop.safety().fault(), servo::SafetyFault::kDeviceError);
  EXPECT_EQ(fakeVendorForce().norm(), 0.0);
  EXPECT_NE(device->faultReason().find("non-finite"), std::string::npos) << device->faultReason();
}

TEST(VendorAdapter, StalledSdkClockIsCountedAsAStall) {
  const auto device = openDevice(uriOf(test::builtFile("HATTR_FAKE_VENDOR_PLUGIN"), "clock=device&stall_after=40"), nullptr);
  servo::ServoLoop loop(*device, servo::ServoConfig{});
  loop.start();
  std::this_thread::sleep_for(150ms);
  loop.stop();
  EXPECT_GE(loop.counters().stalls.load(), 1u);
  EXPECT_LE(loop.counters().ticks.load(), 40u);
}

// ---- A device fault during a trial and during a study --------------------------------

TEST(DeviceFault, EndsTheTrialEarlyWithTheDevicesReasonAndKeepsWhatWasRecorded) {
  session::TrialEnvironment env(uriOf(test::builtFile("HATTR_FAKE_VENDOR_PLUGIN"), "clock=device&error_after=500"), render::WorldConfig{},
                                1000.0);
  // The fake SDK's clock is an ordinary thread: a loaded host (CI runs two sanitized test
  // processes on two cores) can starve it past the trial's 50 ms give-up time, which ends
  // the trial for a clock that stopped calling. Only a counted stall excuses that.
  (void)test::passesUnlessTheHostStalls([&](std::uint64_t& stalls) {
    const test::HostStallWatch watch(stalls, 20ms);
    StillHand hand(HandCommand{.p_target_W = Vec3(0.0, 0.0, 0.005)});
    session::TrialSetup setup{.duration_s = 2.0};
    const auto started = std::chrono::steady_clock::now();
    const session::TrialResult result = session::runTrial(env, setup, hand);
    const double took_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    stalls += result.stalls;
    // What every failure below reports with its own message.
    SCOPED_TRACE(fmt::format("trial: failure \"{}\", {} ticks, {} samples over {:.4f} s, took {:.3f} s, "
                             "{} loop stalls, {} host stalls, {} missed samples",
                             result.failure, result.ticks, result.profile.size(), result.profile.duration_s(), took_s,
                             result.stalls, watch.stalls(), result.missed_samples));
    EXPECT_NE(result.failure.find("error_after=500: plugin:fake-vendor: reading the device: fake SDK: amplifier fault"),
              std::string::npos)
        << result.failure;
    EXPECT_EQ(result.clock, "device");
    // Stopped at the fault (tick 500), not after the 2300 ticks (2.3 s) it was set for.
    EXPECT_LT(result.ticks, 1500u);
    EXPECT_LT(took_s, 2.0);
    EXPECT_GT(result.profile.duration_s(), 0.1);
    const auto& extra = result.profile.metadata().extra;
    ASSERT_TRUE(extra.contains("failed"));
    EXPECT_EQ(extra.at("failed"), result.failure);
    // From the fault on, the loop commanded zero: the last recorded command is zero. (The pen
    // hangs in the air here, so every command is zero; ServoLoop.AFailedReadHoldsTheLastGood...
    // checks that the faulting tick's own sample reaches the recording.)
    ASSERT_FALSE(result.profile.samples().empty());
    EXPECT_EQ(result.profile.samples().back().f_cmd_W.norm(), 0.0);
  });
}

TEST(DeviceFault, AReadThatHangsOnTheLoopsOwnThreadIsAStallNotTheEndOfTheTrial) {
  // A host-clocked loop is hattr's own thread: a gap in its ticks (an SDK call hanging 200 ms,
  // or a host that descheduled it) is counted as a stall and the force ramps in again; only a
  // loop stuck for a second ends the trial.
  session::TrialEnvironment env(uriOf(test::builtFile("HATTR_FAKE_VENDOR_PLUGIN"), "clock=host&block_read_at=600&block_read_ms=200"),
                                render::WorldConfig{}, 1000.0);
  StillHand hand(HandCommand{.p_target_W = Vec3(0.0, 0.0, 0.005)});
  const session::TrialResult result = session::runTrial(env, {.duration_s = 1.0}, hand);
  EXPECT_EQ(result.failure, "");
  EXPECT_EQ(result.clock, "real-time");
  EXPECT_GE(result.stalls, 1u);
}

/// Freezes this whole process `times` times for `frozen_ms`, `every_ms` apart, from a child
/// process (as a host that deschedules the machine does); the child only sleeps and signals.
pid_t freezeThisProcess(int times, long frozen_ms, long every_ms) {
  const pid_t parent = getpid();
  const pid_t child = fork();
  if (child != 0) return child;
  const auto sleepMs = [](long ms) {
    timespec t{ms / 1000, (ms % 1000) * 1000000L};
    while (nanosleep(&t, &t) != 0) {
    }
  };
  for (int i = 0; i < times; ++i) {
    sleepMs(every_ms - frozen_ms);
    kill(parent, SIGSTOP);
    sleepMs(frozen_ms);
    kill(parent, SIGCONT);
  }
  _exit(0);
}

TEST(DeviceFault, ADeviceClockFrozenWithTheWholeProcessIsAStallNotTheEndOfTheTrial) {
  // The trial's watcher is frozen with the device's scheduler: it must not take the host's
  // pause for a device clock that stopped calling (which ends the trial); the loop counts it.
  session::TrialEnvironment env(uriOf(test::builtFile("HATTR_FAKE_VENDOR_PLUGIN"), "clock=device"), render::WorldConfig{}, 1000.0);
  StillHand hand(HandCommand{.p_target_W = Vec3(0.0, 0.0, 0.005)});
  const pid_t freezer = freezeThisProcess(4, 120, 300);
  ASSERT_GT(freezer, 0);
  const session::TrialResult r = session::runTrial(env, {.duration_s = 1.6}, hand);
  int status = 0;
  waitpid(freezer, &status, 0);
  EXPECT_EQ(r.failure, "");
  EXPECT_GE(r.stalls, 1u);
}

TEST(DeviceFault, ADeviceClockThatStopsEndsTheTrial) {
  session::TrialEnvironment env(uriOf(test::builtFile("HATTR_FAKE_VENDOR_PLUGIN"), "clock=device&stall_after=500"), render::WorldConfig{},
                                1000.0);
  StillHand hand(HandCommand{.p_target_W = Vec3(0.0, 0.0, 0.005)});
  const session::TrialResult result = session::runTrial(env, {.duration_s = 2.0}, hand);
  EXPECT_EQ(result.failure, "the device's clock stopped calling the servo loop");
  EXPECT_GE(result.stalls, 1u);
  EXPECT_LT(result.profile.duration_s(), 0.3);
}

/// Sets the fake vendor's process-wide read count (error_after_total) back to zero.
void resetFakeVendorTotalReads(void* plugin) {
  void* symbol = dlsym(plugin, "fake_vendor_reset_total_reads");
  ASSERT_NE(symbol, nullptr);
  void (*hook)() = nullptr;
  std::memcpy(&hook, &symbol, sizeof(hook));
  hook();
}

TEST(DeviceFault, InAStudyMarksTheTrialFailedAndKeepsEveryCompletedTrial) {
  // Each trial opens (and closes) the plugin: the test holds it loaded so the fake's read
  // count spans them all.
  void* held = dlopen(test::builtFile("HATTR_FAKE_VENDOR_PLUGIN"), RTLD_NOW | RTLD_LOCAL);
  ASSERT_NE(held, nullptr);
  (void)test::passesUnlessTheHostStalls([&](std::uint64_t& stalls) {
    // The fake's clock stops calling only when asked to (it is not, here); a thread of this
    // process held up 20 ms says the host starved them, which can end a trial that way (after
    // the 50 ms give-up) or disturb it.
    const test::HostStallWatch watch(stalls, 20ms);
    resetFakeVendorTotalReads(held);
    const test::TempDir dir;
    HapticProfile expert({.subject = "expert", .skill = "dash", .nominal_rate_hz = 100.0});
    for (int i = 0; i <= 20; ++i) {
      Sample s;
      s.t_s = i * 0.01;
      s.p_WT = Vec3(0.001 * i, 0.0, 0.0);
      s.f_user_W = Vec3(0.0, 0.0, -1.0);
      s.pen_down = true;
      expert.append(s);
    }
    io::writeProfileCsv(expert, dir / "expert.csv");
    // Each trial: 0.3 s settling + 0.25 s; the device fails in the third trial.
    test::writeText(dir / "study.json",
                    fmt::format(R"({{"name": "faulty", "skill": "dash", "experts": {{"dash": "expert.csv"}},
      "device": "{}", "modes": ["basic"],
      "protocol": {{"training_trials": 2, "recall_trials": 2, "rest_s": 0, "tail_s": 0.05, "disturbed_trials": "flag"}},
      "world": {{"relief": {{"kind": "flat"}}}}, "subjects": {{"count": 1, "participant": "script"}}}})",
                                uriOf(test::builtFile("HATTR_FAKE_VENDOR_PLUGIN"), "clock=device&error_after_total=1450")));
    auto db = session::StudyDatabase::create(dir / "study.sqlite", session::loadStudy(dir / "study.json"));
    db = session::StudyDatabase::open(dir / "study.sqlite", session::OpenMode::kRunner);
    session::StudyRunner runner(db, &session::makeScriptParticipant);
    std::string message;
    try {
      (void)runner.run(session::RunOptions{.clock = session::Clock::kRealTime});
    } catch (const Error& e) {
      message = e.what();
    }
    const auto trials = db.trials();
    EXPECT_NE(message.find("subject S01: recall trial 1 with BASIC failed: device fault:"), std::string::npos)
        << "message: " << message;
    ASSERT_EQ(trials.size(), 4u);
    EXPECT_EQ(trials[0].status, session::TrialStatus::kCompleted) << trials[0].disturbed;
    EXPECT_EQ(trials[1].status, session::TrialStatus::kCompleted) << trials[1].disturbed;
    EXPECT_EQ(trials[2].status, session::TrialStatus::kInterrupted);
    EXPECT_NE(trials[2].outcome.find("failed: device fault:"), std::string::npos) << trials[2].outcome;
    EXPECT_EQ(trials[3].status, session::TrialStatus::kPending);
    if (trials[0].status != session::TrialStatus::kCompleted || trials[1].status != session::TrialStatus::kCompleted) {
      return;
    }
    EXPECT_GT(db.trialProfile(trials[0].id).duration_s(), 0.2);  // 0.25 s each
    EXPECT_GT(db.trialProfile(trials[1].id).duration_s(), 0.2);
  });
  dlclose(held);
}

}  // namespace
}  // namespace hattr::device
