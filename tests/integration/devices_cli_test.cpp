// `hattr devices`, `hattr devices check` and trials on plugin devices, through the real binary.

#include <sys/wait.h>

#include <cstdlib>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "hattr/io/profile_csv.hpp"
#include "support/host_stalls.hpp"
#include "support/run_command.hpp"
#include "support/test_support.hpp"
#include "support/thread_sanitizer.hpp"

namespace hattr {
namespace {

using ::testing::HasSubstr;

using test::RunResult;

/// Runs hattr with `args` (shell-quoted by the caller), stdin from `input`.
RunResult run(const test::TempDir& dir, const std::string& args, const std::string& input = "") {
  test::writeText(dir / "stdin.txt", input);
  const std::string command = std::string(test::builtFile("HATTR_CLI")) + " " + args + " <" + (dir / "stdin.txt").string() + " >" +
                              (dir / "out.txt").string() + " 2>" + (dir / "err.txt").string();
  const int status = std::system(command.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, test::readText(dir / "out.txt"), test::readText(dir / "err.txt")};
}

std::string quoted(const std::string& text) { return "'" + text + "'"; }

TEST(DevicesCli, ListsTheThreeDeviceKindsTheFoundPluginsAndTheDefaults) {
  test::TempDir dir;
  const RunResult r = run(dir, "devices");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("sim://pen"));
  EXPECT_THAT(r.out, HasSubstr("plugin:/path/libX.so"));
  EXPECT_THAT(r.out, HasSubstr("udp://HOST:PORT?key=FILE"));
  EXPECT_THAT(r.out, HasSubstr("mass_kg                  apparent mass at the tip [kg] in [0.001, 10], default 0.045"));
  EXPECT_THAT(r.out, HasSubstr("libhattr_sim_plugin.so"));
  EXPECT_THAT(r.out, HasSubstr("libhattr_replay_plugin.so"));
  EXPECT_EQ(run(dir, "device").out, r.out);  // the alias
}

TEST(DevicesCli, CheckOnTheSimulatedPenReportsLimitsJitterAndTheGentleForce) {
  test::TempDir dir;
  (void)test::passesUnlessTheHostStalls([&](std::uint64_t& stalls) {
    const RunResult r = run(dir, "devices check sim://pen --no-confirm --seconds 0.3 --json");
    const auto json = nlohmann::json::parse(r.out);
    stalls = json["stalls"].get<std::uint64_t>();
    ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
    EXPECT_TRUE(json["ok"].get<bool>());
    EXPECT_NE(json["verdict"], "FAIL");
    EXPECT_FALSE(json["verdicts"].empty());
    EXPECT_EQ(json["loop_clock"], "real-time");
    EXPECT_DOUBLE_EQ(json["limits"]["continuous_force_N"].get<double>(), 1.75);
    EXPECT_NEAR(json["force_test"]["commanded_N"].get<double>(), 0.2, 0.2 * 0.02);
    EXPECT_GT(json["force_test"]["pen_rise_m"].get<double>(), 3e-4);  // held by a 300 N/m hand: ≈ 0.67 mm
    EXPECT_TRUE(json["force_test"]["confirmed"].is_null());
    // Every tick after the first measured its period.
    EXPECT_GT(json["period_error_us"]["count"].get<int>(), 0);
    EXPECT_LE(json["period_error_us"]["count"].get<int>(), json["ticks"].get<int>());
  });
}

TEST(DevicesCli, CheckRunsADeviceClockedPluginOnItsOwnClock) {
  test::TempDir dir;
  (void)test::passesUnlessTheHostStalls([&](std::uint64_t& stalls) {
    const RunResult r = run(dir, "devices check " + quoted(std::string("plugin:") + test::builtFile("HATTR_SIM_PLUGIN") + "?clock=device") +
                                     " --no-confirm --seconds 0.3 --json");
    const auto json = nlohmann::json::parse(r.out);
    stalls = json["stalls"].get<std::uint64_t>();
    ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
    EXPECT_EQ(json["clocking"], "device");
    EXPECT_EQ(json["loop_clock"], "device");
    EXPECT_GT(json["ticks"].get<int>(), 0);
  });
}

// Issue 38: a stall the check saw is a WARN (the force was zeroed and ramped in again), said in
// the text and the JSON, and the check still passes; a device that faults FAILs it.
TEST(DevicesCli, AStallIsAWarningAndADeviceFaultFailsTheCheck) {
  test::TempDir dir;
  const std::string fake = std::string("plugin:") + test::builtFile("HATTR_FAKE_VENDOR_PLUGIN");
  const RunResult stalled =
      run(dir, "devices check " + quoted(fake + "?clock=device&block_read_at=50&block_read_ms=40") + " --no-confirm --seconds 0.3");
  EXPECT_EQ(stalled.exit_code, 0) << stalled.out << stalled.err;
  EXPECT_THAT(stalled.out, HasSubstr("WARN  stalls"));
  EXPECT_THAT(stalled.out, HasSubstr("verdict WARN"));
  EXPECT_THAT(stalled.out, HasSubstr("check passed with warnings"));

  const RunResult faulty =
      run(dir, "devices check " + quoted(fake + "?clock=device&error_after=100") + " --no-confirm --seconds 0.3 --json");
  EXPECT_EQ(faulty.exit_code, 1) << faulty.out << faulty.err;
  const auto json = nlohmann::json::parse(faulty.out);
  EXPECT_EQ(json["verdict"], "FAIL");
  bool faults_failed = false;
  for (const auto& f : json["verdicts"]) faults_failed = faults_failed || (f["figure"] == "faults" && f["verdict"] == "FAIL");
  EXPECT_TRUE(faults_failed) << faulty.out;
}

TEST(DevicesCli, ThePersonSayingNoFailsTheCheck) {
  test::TempDir dir;
  const RunResult r = run(dir, "devices check sim://pen --seconds 0.2", "n\n");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.out, HasSubstr("person: did NOT feel it"));
  EXPECT_THAT(r.out, HasSubstr("check FAILED"));
  EXPECT_THAT(r.err, HasSubstr("Did you feel a gentle upward push? [y/n]"));
  (void)test::passesUnlessTheHostStalls([&](std::uint64_t& stalls) {
    const RunResult yes = run(dir, "devices check sim://pen --seconds 0.2", "y\n");
    stalls = yes.out.find("WARN  stalls") == std::string::npos ? 0 : 1;
    EXPECT_EQ(yes.exit_code, 0) << yes.out << yes.err;
    EXPECT_THAT(yes.out, HasSubstr("person: felt it"));
  });
}

TEST(DevicesCli, EveryPluginLoadingFailureExitsTwoWithItsMessage) {
  test::TempDir dir;
  test::writeText(dir / "libtext.so", "not ELF");
  const std::pair<std::string, std::string> cases[] = {
      {"plugin:/no/such/libx.so", "file not found"},
      {"plugin:" + (dir / "libtext.so").string(), "not a loadable shared object"},
      {std::string("plugin:") + test::builtFile("HATTR_NO_ENTRY_PLUGIN"), "no entry symbol \"hattr_plugin_entry\""},
      {std::string("plugin:") + test::builtFile("HATTR_ABI_MISMATCH_PLUGIN"), "the plugin speaks version 99, this hattr speaks version 1"},
      {std::string("plugin:") + test::builtFile("HATTR_FAKE_VENDOR_PLUGIN") + "?fail_open=unplugged",
       "the plugin could not open the device: fake SDK: unplugged"},
      {"plugin:nosuchname", "no libhattr_nosuchname_plugin.so in the plugin search path"},
  };
  for (const auto& [uri, expected] : cases) {
    const RunResult r = run(dir, "devices check " + quoted(uri) + " --no-confirm");
    EXPECT_EQ(r.exit_code, 2) << uri;
    EXPECT_THAT(r.err, HasSubstr(expected)) << uri;
  }
}

TEST(DevicesCli, TrainOnTheSimPluginWritesTheSameSamplesAsOnSimPen) {
  HATTR_STARTS_NO_THREAD();
  test::TempDir dir;
  // An expert recorded on sim://pen, then the same training trial on both devices.
  test::writeText(dir / "hand.csv",
                  "t_s,x_m,y_m,z_m,fx_N,fy_N,fz_N,pen_down_bool\n0,0,0,0,0,0,-1,1\n0.2,0.01,0,0,0,0,-1,1\n"
                  "0.4,0.01,0.01,0,0,0,-1,1\n");
  ASSERT_EQ(run(dir, "record --hand " + (dir / "hand.csv").string() + " -o " + (dir / "expert.csv").string()).exit_code, 0);
  const std::string common = " --mode alpha --hand " + (dir / "hand.csv").string() + " --reference " +
                             (dir / "expert.csv").string() + " -o ";
  const RunResult direct = run(dir, "train --device sim://pen" + common + (dir / "direct.csv").string());
  ASSERT_EQ(direct.exit_code, 0) << direct.err;
  const RunResult plugged =
      run(dir, "train --device plugin:sim" + common + (dir / "plugged.csv").string() + " --json");
  ASSERT_EQ(plugged.exit_code, 0) << plugged.err;
  EXPECT_EQ(nlohmann::json::parse(plugged.out)["clock"], "simulated");
  const HapticProfile a = io::readProfileCsv(dir / "direct.csv");
  const HapticProfile b = io::readProfileCsv(dir / "plugged.csv");
  ASSERT_EQ(a.size(), b.size());
  EXPECT_TRUE(a.samples() == b.samples());
  EXPECT_EQ(b.metadata().device, "plugin:sim");
}

TEST(DevicesCli, ADeviceFaultMidTrialExitsOneAndKeepsWhatWasRecorded) {
  test::TempDir dir;
  test::writeText(dir / "hand.csv", "t_s,x_m,y_m,z_m,fx_N,fy_N,fz_N,pen_down_bool\n0,0,0,0,0,0,-1,1\n2,0.01,0,0,0,0,-1,1\n");
  const std::string uri = std::string("plugin:") + test::builtFile("HATTR_FAKE_VENDOR_PLUGIN") + "?clock=device&error_after=600";
  const RunResult r = run(dir, "record --device " + quoted(uri) + " --hand " + (dir / "hand.csv").string() + " -o " +
                                   (dir / "partial.csv").string());
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("the trial failed after"));
  EXPECT_THAT(r.err, HasSubstr("fake SDK: amplifier fault (SDK error 513)"));
  const HapticProfile partial = io::readProfileCsv(dir / "partial.csv");
  // Kept up to the fault: some samples, and fewer than the 600 ticks after which the device
  // failed (ticks, not seconds: a stalled host stretches time, not the tick count).
  EXPECT_GT(partial.size(), 0u);
  EXPECT_LT(partial.size(), 600u);
  EXPECT_THAT(partial.metadata().extra.at("failed"), HasSubstr("amplifier fault"));
}

}  // namespace
}  // namespace hattr
