// The scheduled strategies across trials and sessions (issue 36): each guided trial's law and
// gain follow from the tracking errors stored with the trials before it, in a study stopped
// mid-schedule, killed with SIGKILL and resumed; the trials are the same to the bit as an
// unbroken run's.

#include <signal.h>

#include <algorithm>
#include <chrono>
#include <random>
#include <string>
#include <thread>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "hattr/guidance/reference.hpp"
#include "hattr/guidance/strategy_schedule.hpp"
#include "hattr/session/study_database.hpp"
#include "support/run_command.hpp"
#include "support/test_support.hpp"
#include "support/thread_sanitizer.hpp"

namespace hattr {
namespace {

using test::RunResult;
using test::runHattr;

/// Three groups, one scheduled strategy each with parameters of the study's own, over two sessions.
constexpr std::string_view kStudy = R"({
  "format": "hattr-study/1", "name": "schedules", "skill": "na", "experts": {"na": "na"},
  "protocol": {"rest_s": 0, "trial_end": {"pen_up_s": 1.0, "max_s": 0}},
  "order": {"kind": "fixed"}, "device": "sim://pen", "world": {"relief": {"kind": "flat"}}, "rate_hz": 1000,
  "strategy_parameters": {
    "assist-as-needed": {"start_gain": 0.8, "forgetting": 0.7, "error_gain_per_mm": 0.2, "deadband_mm": 0.3},
    "fading": {"base": "alpha", "trials": 4, "end_gain": 0.1},
    "partial-then-full": {"partial_trials": 3},
    "channel": {"half_width_mm": 1}
  },
  "groups": [
    {"name": "aan", "strategies": ["assist-as-needed"], "subjects": {"count": 1, "prefix": "N"}},
    {"name": "fade", "strategies": ["fading"], "subjects": {"count": 1, "prefix": "F"}},
    {"name": "ptf", "strategies": ["partial-then-full"], "subjects": {"count": 1, "prefix": "P"}}
  ],
  "sessions": [
    {"day": 0, "blocks": [{"phase": "training", "strategy": "group", "trials": 4}, {"phase": "post-test", "trials": 1}]},
    {"day": 1, "blocks": [{"phase": "training", "strategy": "group", "trials": 3}]}
  ]
})";

double number(const std::map<std::string, std::string>& extra, const std::string& key) {
  const auto it = extra.find(key);
  EXPECT_NE(it, extra.end()) << key;
  return it == extra.end() ? NAN : std::stod(it->second);
}

TEST(StrategyScheduleCli, EachGuidedTrialsGainFollowsTheStoredErrorsThroughAKillAndAResume) {
  HATTR_SKIP_UNDER_THREAD_SANITIZER("the CLI runs the study on one thread; the schedule's arithmetic is the same "
                                    "under every build");
  test::TempDir dir;
  test::writeText(dir / "study.json", std::string(kStudy));
  const std::string reference_db = (dir / "reference.sqlite").string(), crash_db = (dir / "crash.sqlite").string();
  for (const std::string& db : {reference_db, crash_db}) {
    const RunResult init = runHattr(dir, fmt::format("study init {} --db {}", (dir / "study.json").string(), db));
    ASSERT_EQ(init.exit_code, 0) << init.err;
  }
  ASSERT_EQ(runHattr(dir, "study run --quiet --db " + reference_db).exit_code, 0);

  // Stopped after two trials (the first subject in its first block), then killed at a random
  // moment, then resumed to the end.
  ASSERT_EQ(runHattr(dir, "study run --quiet --max-trials 2 --db " + crash_db).exit_code, 0);
  std::mt19937_64 rng(test::testSeed(36));
  const pid_t pid = test::spawnProcess({test::builtFile("HATTR_CLI"), "study", "run", "--quiet", "--db", crash_db});
  std::this_thread::sleep_for(std::chrono::milliseconds(std::uniform_int_distribution<int>(20, 300)(rng)));
  ::kill(pid, SIGKILL);
  (void)test::exitStatus(pid);
  const RunResult resumed = runHattr(dir, "study run --quiet --db " + crash_db);
  ASSERT_EQ(resumed.exit_code, 0) << resumed.err;

  const auto reference = session::StudyDatabase::open(reference_db, session::OpenMode::kReadOnly);
  const auto crashed = session::StudyDatabase::open(crash_db, session::OpenMode::kReadOnly);
  const auto a = reference.trials(), b = crashed.trials();
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(b[i].status, session::TrialStatus::kCompleted);
    ASSERT_EQ(crashed.trialProfile(b[i].id), reference.trialProfile(a[i].id)) << "trial " << i;
  }

  // Each subject's guided trials, in order: the law and gain its schedule owed them.
  const guidance::ReferenceTrajectory expert(crashed.expert("na"), 1000.0);
  std::map<std::string, std::vector<std::pair<std::string, double>>> laws;  // subject -> (law, gain)
  std::map<std::string, std::vector<double>> errors;
  for (const auto& t : b) {
    const HapticProfile profile = crashed.trialProfile(t.id);
    const auto& extra = profile.metadata().extra;
    if (!t.plan.view.guidance) {
      EXPECT_FALSE(extra.contains("guidance_gain")) << t.plan.subject << " " << t.plan.sequence;
      continue;
    }
    // The stored error is the trial's own, and the one TrialRecord hands the next trial.
    const double error = guidance::trackingErrorRms(expert, profile);
    EXPECT_EQ(extra.at("tracking_rms_m"), fmt::format("{}", error));
    EXPECT_EQ(t.strategy_state.at("tracking_rms_m"), extra.at("tracking_rms_m"));
    laws[t.plan.subject].emplace_back(extra.at("guidance_law"), number(extra, "guidance_gain"));
    errors[t.plan.subject].push_back(error);
  }
  // ASSIST-AS-NEEDED: g₁ = 0.8, g_{n+1} = clamp(0.7·g_n + 0.2/mm·max(0, e_n − 0.3 mm), 0, 1).
  ASSERT_EQ(laws["N01"].size(), 7u);
  double g = 0.8;
  std::set<double> gains;
  for (std::size_t n = 0; n < laws["N01"].size(); ++n) {
    EXPECT_EQ(laws["N01"][n].first, "PCONTROL");
    EXPECT_NEAR(laws["N01"][n].second, g, 1e-12) << n;
    gains.insert(laws["N01"][n].second);
    g = std::clamp(0.7 * g + 200.0 * std::max(0.0, errors["N01"][n] - 0.0003), 0.0, 1.0);
  }
  EXPECT_GE(gains.size(), 3u) << "the gain followed the errors";
  // FADING of ALPHA over 4 guided trials to 0.1, across the sessions.
  const std::vector<double> faded{1.0, 0.7, 0.4, 0.1, 0.1, 0.1, 0.1};
  ASSERT_EQ(laws["F01"].size(), faded.size());
  for (std::size_t n = 0; n < faded.size(); ++n) {
    EXPECT_EQ(laws["F01"][n].first, "ALPHA");
    EXPECT_NEAR(laws["F01"][n].second, faded[n], 1e-12) << n;
  }
  // PARTIAL-THEN-FULL: the channel for 3 guided trials, then the guided path.
  ASSERT_EQ(laws["P01"].size(), 7u);
  for (std::size_t n = 0; n < laws["P01"].size(); ++n) {
    EXPECT_EQ(laws["P01"][n], (std::pair<std::string, double>(n < 3 ? "CHANNEL" : "PCONTROL", 1.0))) << n;
  }
}

}  // namespace
}  // namespace hattr
