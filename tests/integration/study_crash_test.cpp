// Kills `hattr study run` with SIGKILL at random moments, many times, resuming after each,
// and checks that every completed trial is intact and bit-identical to an uninterrupted run.

#include <signal.h>

#include <chrono>
#include <random>
#include <thread>

#include <gtest/gtest.h>

#include "hattr/io/profile_csv.hpp"
#include "hattr/session/study_database.hpp"
#include "support/run_command.hpp"
#include "support/test_support.hpp"
#include "support/thread_sanitizer.hpp"

namespace hattr {
namespace {

/// Starts `hattr study run --db FILE --quiet`; returns the child's pid.
pid_t startRunner(const std::filesystem::path& db) {
  return test::spawnProcess({test::builtFile("HATTR_CLI"), "study", "run", "--db", db.string(), "--quiet"});
}

void makeStudy(const test::TempDir& dir, const std::string& db) {
  HapticProfile expert({.subject = "expert", .skill = "dash", .nominal_rate_hz = 100.0});
  for (int i = 0; i <= 40; ++i) {
    Sample s;
    s.t_s = i * 0.01;
    s.p_WT = Vec3(0.001 * i, 0.0005 * i, 0.0);
    s.f_user_W = Vec3(0.0, 0.0, -1.0);
    s.pen_down = true;
    expert.append(s);
  }
  if (!std::filesystem::exists(dir / "expert.csv")) io::writeProfileCsv(expert, dir / "expert.csv");
  test::writeText(dir / "study.json", R"({"name": "crash", "skill": "dash", "experts": {"dash": "expert.csv"},
      "protocol": {"training_trials": 4, "recall_trials": 3, "rest_s": 0, "tail_s": 0.05},
      "world": {"relief": {"kind": "flat"}},
      "subjects": {"count": 2, "participant": "script", "options": {"jitter_mm": 0.5}}})");
  (void)session::StudyDatabase::create(dir / db, session::loadStudy(dir / "study.json"));
}

TEST(StudyCrash, KilledRunnerResumesWithEveryCompletedTrialIntactAndIdentical) {
  HATTR_STARTS_NO_THREAD();
  test::TempDir dir;
  makeStudy(dir, "reference.sqlite");
  makeStudy(dir, "crash.sqlite");
  ASSERT_EQ(test::exitStatus(startRunner(dir / "reference.sqlite")), 0);

  // Kill the runner at random moments until one finishes on its own.
  const std::uint64_t seed = test::testSeed(2026);
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> delay_ms(20, 80);  // start-up takes about 50 ms
  int kills = 0;
  for (int attempt = 0; attempt < 40; ++attempt) {
    const pid_t pid = startRunner(dir / "crash.sqlite");
    std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms(rng)));
    if (::kill(pid, SIGKILL) == 0) {
      const int status = test::exitStatus(pid);
      if (status == 0) break;  // it finished before the signal landed
      ASSERT_EQ(status, -SIGKILL) << "seed " << seed;
      ++kills;
    } else {
      ASSERT_EQ(test::exitStatus(pid), 0) << "seed " << seed;
      break;
    }
  }
  ASSERT_EQ(test::exitStatus(startRunner(dir / "crash.sqlite")), 0) << "the final resume must complete the study";

  const auto reference = session::StudyDatabase::open(dir / "reference.sqlite", session::OpenMode::kReadOnly);
  const auto crashed = session::StudyDatabase::open(dir / "crash.sqlite", session::OpenMode::kReadOnly);
  const auto ref_trials = reference.trials();
  const auto crash_trials = crashed.trials();
  ASSERT_EQ(ref_trials.size(), 42u);
  ASSERT_EQ(crash_trials.size(), ref_trials.size());
  int interrupted = 0;
  for (std::size_t i = 0; i < ref_trials.size(); ++i) {
    ASSERT_EQ(crash_trials[i].status, session::TrialStatus::kCompleted) << "trial " << i << " seed " << seed;
    EXPECT_EQ(crashed.trialProfile(crash_trials[i].id), reference.trialProfile(ref_trials[i].id))
        << "trial " << i << " differs from the uninterrupted run (seed " << seed << ")";
    interrupted += crash_trials[i].interruptions;
  }
  std::cout << "[ info ] " << kills << " kills, " << interrupted << " trials interrupted mid-way and run again\n";
  EXPECT_GE(kills, 3) << "the runner should have been killed several times (seed " << seed << ")";
}

}  // namespace
}  // namespace hattr
