// A trial and a study over udp:// against a device server with a simulated pen on this
// machine, compared with the same trial on sim://pen directly.

#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "hattr/analysis/dtw.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/net/device_server.hpp"
#include "hattr/session/study_runner.hpp"
#include "hattr/session/trial.hpp"
#include "support/test_support.hpp"

namespace hattr::net {
namespace {

struct Served {
  test::TempDir dir;
  std::filesystem::path key_file = dir / "shared.key";
  std::unique_ptr<DeviceServer> server;
  Served() {
    wire::writeKeyFile(key_file, wire::randomKey(), false);
    DeviceServerConfig config;
    config.device_uri = "sim://pen";
    config.key = wire::readKeyFile(key_file);
    server = std::make_unique<DeviceServer>(config);
    server->start();
  }
  /// hold_ms=20: this 2-core machine without real-time privileges oversleeps the default 5 ms
  /// now and then with two servo loops on it (docs/BENCHMARKS.md); a dropout is not what the
  /// comparison is about.
  [[nodiscard]] std::string uri() const {
    return "udp://" + server->endpoint().text() + "?key=" + key_file.string() + "&hold_ms=20";
  }
};

/// A figure-of-eight written in 1.5 s, pressing 1.2 N.
HapticProfile script() {
  HapticProfile p;
  for (int i = 0; i <= 150; ++i) {
    Sample s;
    s.t_s = i * 0.01;
    const double a = 2.0 * 3.141592653589793 * s.t_s / 1.5;
    s.p_WT = Vec3(0.02 * std::sin(a), 0.01 * std::sin(2 * a), 0.0);
    s.v_WT = Vec3(0.02 * std::cos(a), 0.02 * std::cos(2 * a), 0.0) * (2.0 * 3.141592653589793 / 1.5);
    s.f_user_W = Vec3(0.0, 0.0, -1.2);
    s.pen_down = true;
    p.append(s);
  }
  return p;
}

session::TrialResult trainOn(const std::string& uri, const HapticProfile& expert) {
  session::TrialEnvironment env(uri, render::WorldConfig{}, 1000.0);
  device::ProfileHandScript hand(script(), 1.0471975511965976, Vec3(0.0, 0.002, 0.0));
  session::TrialSetup setup{.duration_s = 1.7};
  setup.guidance.mode = guidance::TrainingMode::kPositionControl;
  setup.reference = std::make_shared<guidance::ReferenceTrajectory>(expert, 1000.0);
  setup.clock = session::Clock::kRealTime;
  return session::runTrial(env, setup, hand);
}

/// Mean |difference| along the DTW path per sample, as a fraction of the channel's scale in
/// the direct trial (its largest magnitude: the glyph's half-width, the pressing force).
double relativeDtw(const HapticProfile& direct, const HapticProfile& remote, const char* channel) {
  const auto a = direct.channel(channel);
  const auto b = remote.channel(channel);
  double scale = 0.0;
  for (const double v : a) scale = std::max(scale, std::abs(v));
  const double cost = analysis::dtwDistance(a, b);
  return cost / static_cast<double>(std::max(a.size(), b.size())) / scale;
}

/// A real-time trial the machine disturbed: a late tick of a few ms holds a stale paper force
/// over the simulated pen, a stall or a dropout zeroes it, and the simulated hand pushes the pen
/// deep into the paper (seen on this 2-core virtual machine, on sim://pen as on udp://); such a
/// pair compares the machine's hiccups, not the network. The server's loop counts too.
bool disturbed(const session::TrialResult& r, std::uint64_t server_overruns) {
  return r.stalls > 0 || r.link_faults > 0 || r.max_period_error_s > 0.002 || server_overruns > 0;
}

TEST(UdpTrial, ProfileOverTheNetworkIsCloseToTheSameTrialOnTheSimulatedPen) {
  Served served;
  session::TrialEnvironment expert_env("sim://pen", render::WorldConfig{}, 1000.0);
  device::ProfileHandScript expert_hand(script());
  const HapticProfile expert = session::runTrial(expert_env, {.duration_s = 1.7}, expert_hand).profile;

  // Up to three pairs, compared on the first the machine left undisturbed.
  std::string attempts;
  for (int attempt = 1; attempt <= 3; ++attempt) {
    const session::TrialResult direct = trainOn("sim://pen", expert);
    const std::uint64_t server_overruns_before = served.server->stats().overruns;
    const session::TrialResult remote = trainOn(served.uri(), expert);
    const std::uint64_t server_overruns = served.server->stats().overruns - server_overruns_before;
    ASSERT_TRUE(remote.failure.empty()) << remote.failure;
    attempts += fmt::format(" [{}: direct max late {:.1f} ms, {} stalls; udp max late {:.1f} ms, {} stalls, {} link "
                            "faults, server {} overruns]",
                            attempt, direct.max_period_error_s * 1e3, direct.stalls, remote.max_period_error_s * 1e3,
                            remote.stalls, remote.link_faults, server_overruns);
    if (disturbed(direct, 0) || disturbed(remote, server_overruns)) continue;
    EXPECT_EQ(remote.clock, "real-time");
    EXPECT_GT(remote.profile.penDownCount(), 1000u);
    for (const char* channel : {"x", "y", "fz"}) {
      const double relative = relativeDtw(direct.profile, remote.profile, channel);
      std::printf("udp vs sim://pen, %s: mean DTW difference %.3f %% of the channel's scale\n", channel, 100.0 * relative);
      EXPECT_LT(relative, 0.03) << channel;
    }
    return;
  }
  // A machine whose scheduler stalls every real-time trial (a noisy virtual machine: the bare
  // sleep loop of `hattr servo-check` then shows period errors of 5-13 ms) cannot answer the
  // question; say so rather than fail or pass.
  GTEST_SKIP() << "every pair was disturbed by this machine's scheduling (stalls zero the force):" << attempts;
}

TEST(UdpTrial, AStudyRunsOverTheNetworkDevice) {
  Served served;
  HapticProfile expert({.subject = "expert", .skill = "dash", .nominal_rate_hz = 100.0});
  for (int i = 0; i <= 20; ++i) {
    Sample s;
    s.t_s = i * 0.01;
    s.p_WT = Vec3(0.001 * i, 0.0, 0.0);
    s.f_user_W = Vec3(0.0, 0.0, -1.0);
    s.pen_down = true;
    expert.append(s);
  }
  io::writeProfileCsv(expert, served.dir / "expert.csv");
  test::writeText(served.dir / "study.json",
                  fmt::format(R"({{"name": "remote", "skill": "dash", "experts": {{"dash": "expert.csv"}},
    "device": "{}", "modes": ["pcontrol"],
    "protocol": {{"training_trials": 1, "recall_trials": 1, "rest_s": 0, "tail_s": 0.05}},
    "world": {{"relief": {{"kind": "flat"}}}}, "subjects": {{"count": 1, "participant": "script"}}}})",
                              served.uri()));
  auto db = session::StudyDatabase::create(served.dir / "s.sqlite", session::loadStudy(served.dir / "study.json"));
  db = session::StudyDatabase::open(served.dir / "s.sqlite", session::OpenMode::kRunner);
  session::StudyRunner runner(db, &session::makeScriptParticipant);
  EXPECT_EQ(runner.run({}), 2);
  int attempts = 0;
  for (const auto& trial : db.trials()) {
    EXPECT_EQ(trial.status, session::TrialStatus::kCompleted);
    attempts += trial.attempts;
    const HapticProfile p = db.trialProfile(trial.id);
    EXPECT_EQ(p.metadata().extra.at("clock"), "real-time");
    EXPECT_EQ(p.metadata().device, served.uri());
    EXPECT_GT(p.duration_s(), 0.2);  // 0.25 s (the sample count depends on the ticks a late loop skips)
  }
  // Each attempt of a trial opened the device once, and nothing opened it only to read its limits
  // (issue 63): one session an attempt, ended by the client's goodbye. Two trials are two attempts
  // unless the host disturbed one (ThreadSanitizer's, in the CI run of 4daf169): the study runs it again, with
  // its own open. (A session left silent for its timeout makes the client say hello again: more
  // sessions, no more goodbyes.)
  EXPECT_GE(attempts, 2);
  const DeviceServerStats stats = served.server->stats();
  EXPECT_EQ(stats.byes, static_cast<std::uint64_t>(attempts))
      << attempts << " attempts, " << stats.sessions << " sessions, " << stats.session_timeouts << " ended by silence";
}

}  // namespace
}  // namespace hattr::net
