// Three stations (`hattr study run` processes) run one 30-subject simulated study (12 under the sanitizers) against one
// PostgreSQL server (a throwaway one this test starts); one of them is killed with SIGKILL
// twice along the way and started again. Every trial must be completed once, nothing lost, and
// every trial and the analysis the same as the same study run by one station on SQLite.

#include <signal.h>

#include <chrono>
#include <thread>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/io/profile_csv.hpp"
#include "hattr/session/study_database.hpp"
#include "support/postgres_cluster.hpp"
#include "support/run_command.hpp"
#include "support/test_support.hpp"
#include "support/thread_sanitizer.hpp"

namespace hattr {
namespace {

/// 30 subjects (360 trials) in release; under the sanitizers 12 (144 trials: the kills still
/// fall a quarter and two thirds of the way, with all three stations running).
constexpr int kSubjects = test::kSanitized ? 12 : 30;
constexpr int kTrialsPerSubject = 12;  // 3 modes × (2 training + 2 recall)

/// Starts `hattr study run --db ADDRESS --quiet --lease-timeout 5`, its stderr in `err`.
pid_t startStation(const std::string& address, const std::filesystem::path& err) {
  return test::spawnProcess({test::builtFile("HATTR_CLI"), "study", "run", "--db", address, "--quiet", "--lease-timeout", "5"}, err);
}

void writeStudy(const test::TempDir& dir) {
  HapticProfile expert({.subject = "expert", .skill = "dash", .nominal_rate_hz = 100.0});
  for (int i = 0; i <= 40; ++i) {
    Sample s;
    s.t_s = i * 0.01;
    s.p_WT = Vec3(0.001 * i, 0.0005 * i, 0.0);
    s.f_user_W = Vec3(0.0, 0.0, -1.0);
    s.pen_down = true;
    expert.append(s);
  }
  io::writeProfileCsv(expert, dir / "expert.csv");
  test::writeText(dir / "study.json", fmt::format(R"({{"name": "stations", "skill": "dash",
      "experts": {{"dash": "expert.csv"}},
      "protocol": {{"training_trials": 2, "recall_trials": 2, "rest_s": 0, "tail_s": 0.05}},
      "world": {{"relief": {{"kind": "flat"}}}},
      "subjects": {{"count": {}, "participant": "simulated"}}}})",
                                                  kSubjects));
}

int completedTrials(const session::StudyDatabase& db) {
  int n = 0;
  for (const auto& t : db.trials()) n += t.status == session::TrialStatus::kCompleted ? 1 : 0;
  return n;
}

TEST(StudyStations, ThreeStationsOneKilledTwiceRunTheStudyAsOneStationOnSqlite) {
  test::TempDir dir;
  writeStudy(dir);
  const std::string cli = test::builtFile("HATTR_CLI");
  const std::string address = test::PostgresCluster::shared().createDatabase("stations");
  ASSERT_EQ(test::runCommand(dir, cli, "study init " + (dir / "study.json").string() + " --db '" + address + "'", "init")
                .exit_code,
            0);

  // Three stations; station 0 is killed when a quarter and when two thirds of the trials are
  // done, and started again each time.
  const int total = kSubjects * kTrialsPerSubject;
  const session::StudyDatabase watch = session::StudyDatabase::open(address, session::OpenMode::kReadOnly);
  std::vector<pid_t> stations;
  for (int s = 0; s < 3; ++s) stations.push_back(startStation(address, dir / fmt::format("station{}.err", s)));
  int kills = 0;
  for (const int kill_at : {total / 4, 2 * total / 3}) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(10);
    while (completedTrials(watch) < kill_at && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    if (::kill(stations[0], SIGKILL) == 0 && test::exitStatus(stations[0]) == -SIGKILL) ++kills;
    stations[0] = startStation(address, dir / "station0.err");
  }
  EXPECT_EQ(kills, 2) << "station 0 ended before it could be killed twice";
  for (std::size_t s = 0; s < stations.size(); ++s) {
    EXPECT_EQ(test::exitStatus(stations[s]), 0) << test::readText(dir / fmt::format("station{}.err", s));
  }

  // Every trial completed once, with its samples; the killed station's running trial (if it
  // was in one) interrupted and run again, and a disturbed attempt (a simulated trainee who
  // presses harder than the pen renders sinks through the paper) run again by the policy.
  const auto trials = watch.trials();
  ASSERT_EQ(static_cast<int>(trials.size()), total);
  int interruptions = 0;
  for (const auto& t : trials) {
    EXPECT_EQ(t.status, session::TrialStatus::kCompleted) << t.plan.subject << " " << t.plan.sequence;
    EXPECT_GT(t.sample_count, 0);
    EXPECT_EQ(t.attempts, 1 + t.interruptions + t.disturbed_attempts) << t.plan.subject << " " << t.plan.sequence;
    interruptions += t.interruptions;
  }
  EXPECT_LE(interruptions, 2);
  // No lease outlives its timeout (5 s): one the killed station held when the others finished
  // (they were done with its subject, or took it over) lapses then. Under AddressSanitizer the
  // last third of the trials once took less than 5 s after the second kill.
  const auto lapse_deadline = std::chrono::steady_clock::now() + std::chrono::seconds(6);
  while (watch.runnerActive() && std::chrono::steady_clock::now() < lapse_deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  EXPECT_FALSE(watch.runnerActive());

  // The same study on SQLite, one station: the same trials to the bit, the same analysis.
  const auto file = dir / "one.sqlite";
  ASSERT_EQ(test::runCommand(dir, cli, "study init " + (dir / "study.json").string() + " --db " + file.string(), "init1")
                .exit_code,
            0);
  ASSERT_EQ(test::runCommand(dir, cli, "study run --quiet --db " + file.string(), "run1").exit_code, 0);
  const session::StudyDatabase one = session::StudyDatabase::open(file, session::OpenMode::kReadOnly);
  const auto reference = one.trials();
  ASSERT_EQ(reference.size(), trials.size());
  for (std::size_t i = 0; i < trials.size(); ++i) {
    ASSERT_EQ(trials[i].plan.subject, reference[i].plan.subject);
    ASSERT_EQ(trials[i].plan.sequence, reference[i].plan.sequence);
    EXPECT_EQ(watch.trialProfile(trials[i].id), one.trialProfile(reference[i].id))
        << trials[i].plan.subject << " " << trials[i].plan.sequence;
  }
  const auto analyzed = test::runCommand(dir, cli, "study analyze --db '" + address + "' --out " + (dir / "pg").string(), "a");
  ASSERT_EQ(analyzed.exit_code, 0) << analyzed.err;
  ASSERT_EQ(test::runCommand(dir, cli, "study analyze --db " + file.string() + " --out " + (dir / "lite").string(), "b")
                .exit_code,
            0);
  for (const char* table : {"recall_costs.csv", "anova.csv", "table1.csv"}) {
    EXPECT_EQ(test::readText(dir / "pg" / table), test::readText(dir / "lite" / table)) << table;
  }
  // The report reads the server's study as it reads a file.
  const auto reported = test::runCommand(dir, cli, "study report --db '" + address + "' --out " + (dir / "report").string(), "r");
  EXPECT_EQ(reported.exit_code, 0) << reported.err;
  EXPECT_TRUE(std::filesystem::exists(dir / "report" / "report.html"));
}

}  // namespace
}  // namespace hattr
