#include <sqlite3.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/session/study_export.hpp"
#include "hattr/session/study_runner.hpp"
#include "session/study_fixture.hpp"
#include "support/test_support.hpp"
#include "support/thread_sanitizer.hpp"

namespace hattr::session {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::Not;

std::string smallStudy(int subjects = 2) {
  return fmt::format(R"({{"name": "small", "skill": "dash", "experts": {{"dash": "expert.csv"}},
    "modes": ["basic", "pcontrol", "alpha"],
    "protocol": {{"training_trials": 2, "recall_trials": 1, "rest_s": 0, "tail_s": 0.05}},
    "world": {{"relief": {{"kind": "flat"}}}},
    "subjects": {{"count": {}, "participant": "script", "options": {{"jitter_mm": 1.0}}}}}})",
                     subjects);
}

struct StudyFolder {
  StudyFolder(const std::string& definition = smallStudy()) {
    writeExpert(dir / "expert.csv");
    test::writeText(dir / "study.json", definition);
  }
  test::TempDir dir;
};

std::string studyError(const std::string& json, const std::filesystem::path& base) {
  try {
    (void)parseStudy(json, "study.json", base);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(StudyDefinition, ValidationNamesEveryProblemAtOnce) {
  test::TempDir dir;
  const std::string message = studyError(R"({"name": "x", "skill": "na", "experts": {"na": "missing.csv"},
      "modes": ["basic", "gamma", "basic"], "protocol": {"training_trials": 0, "recall_trials": 0},
      "subjects": [{"id": "S1"}, {"id": "S1"}], "colour": "red"})",
                                         dir.path());
  EXPECT_THAT(message, HasSubstr("study.json: 6 problems in the study definition:"));
  EXPECT_THAT(message, HasSubstr("unknown key \"colour\""));
  EXPECT_THAT(message, HasSubstr("experts.na: expert file"));
  EXPECT_THAT(message, HasSubstr("modes: mode: expected one of basic, pcontrol, alpha, mentor-observe, mentor-position, "
                                 "mentor-force, mentor-bilateral, channel, error-augmentation, noise, playback, fading, "
                                 "assist-as-needed, partial-then-full, got \"gamma\""));
  EXPECT_THAT(message, HasSubstr("modes: \"basic\" listed twice"));
  EXPECT_THAT(message, HasSubstr("protocol: zero trials per mode"));
  EXPECT_THAT(message, HasSubstr("subjects[1]: id \"S1\" used twice"));
}

TEST(StudyDefinition, DefaultsAreThePapersProtocol) {
  StudyFolder folder(R"({"name": "x", "skill": "dash", "experts": {"dash": "expert.csv"}, "subjects": {"count": 1}})");
  const StudyDefinition s = loadStudy(folder.dir / "study.json");
  EXPECT_EQ(s.modes.size(), 3u);
  EXPECT_EQ(s.protocol.training_trials, 11);
  EXPECT_EQ(s.protocol.recall_trials, 11);
  EXPECT_EQ(s.protocol.rest_s, 10.0);
  EXPECT_FALSE(s.protocol.recall.show_reference);
  EXPECT_FALSE(s.protocol.recall.guidance);
  EXPECT_EQ(planTrials(s, s.subjects.front(), s.modes).size(), 66u);
}

TEST(StudyDefinition, AMentorBlockSaysWhoMentorsAndSurvivesTheDatabase) {
  test::TempDir dir;
  writeExpert(dir / "expert.csv");
  test::writeText(dir / "mentor.key", "not checked here");
  const std::string head = R"({"name": "m", "skill": "dash", "experts": {"dash": "expert.csv"},
      "modes": ["basic", "MENTOR-Bilateral"], "subjects": {"count": 1}, "mentor": )";

  // A simulated expert with its link, read back from the definition's JSON unchanged.
  const StudyDefinition s = parseStudy(head + R"({"expert": "simulated", "round_trip_ms": 80, "jitter_ms": 2,
      "loss_percent": 5, "passivity": false, "deadband": 0.1, "expert_device": "sim://pen?mass_kg=0.05"}})",
                                       "study.json", dir.path());
  EXPECT_TRUE(s.hasMentoredModes());
  EXPECT_EQ(s.modes[1], guidance::TrainingMode::kMentorBilateral);
  EXPECT_DOUBLE_EQ(s.mentor.round_trip_s, 0.08);
  EXPECT_DOUBLE_EQ(s.mentor.loss, 0.05);
  EXPECT_FALSE(s.mentor.passivity);
  const StudyDefinition again = parseStudy(studyToJson(s).dump(), "stored", dir.path());
  EXPECT_EQ(studyToJson(again), studyToJson(s));

  // A live expert: where, and the key (relative to the study file).
  const StudyDefinition live =
      parseStudy(head + R"({"expert": "live", "connect": "10.0.0.2:7400", "key": "mentor.key"}})", "study.json", dir.path());
  EXPECT_EQ(live.mentor.key, dir.path() / "mentor.key");
  EXPECT_EQ(parseStudy(studyToJson(live).dump(), "stored", dir.path()).mentor.connect, "10.0.0.2:7400");

  // Every problem named.
  const std::string message = studyError(head + R"({"expert": "live", "loss_percent": 80, "colour": 1}})", dir.path());
  EXPECT_THAT(message, HasSubstr("mentor: unknown key \"colour\""));
  EXPECT_THAT(message, HasSubstr("mentor.loss_percent: expected a number in [0, 50], got 80"));
  EXPECT_THAT(message, HasSubstr("mentor.connect: a live expert needs HOST:PORT"));
  EXPECT_THAT(message, HasSubstr("mentor.key: a live expert needs the key file"));
  EXPECT_THAT(studyError(head + R"({"expert": "ghost"}})", dir.path()),
              HasSubstr("mentor.expert: expected \"simulated\" or \"live\", got \"ghost\""));
  EXPECT_THAT(studyError(head + R"({"expert": "live", "connect": "h:1", "key": "nope.key"}})", dir.path()),
              HasSubstr("mentor.key: key file"));
}

TEST(StudyDefinition, LatinSquareCounterbalancesOrderAndCarryOver) {
  StudyFolder folder(smallStudy(6));
  const StudyDefinition s = loadStudy(folder.dir / "study.json");
  const auto orders = modeOrders(s);
  std::set<std::vector<guidance::TrainingMode>> distinct(orders.begin(), orders.end());
  EXPECT_EQ(distinct.size(), 6u);  // three modes: all six sequences
  std::map<guidance::TrainingMode, int> first;
  std::map<std::pair<guidance::TrainingMode, guidance::TrainingMode>, int> follows;
  for (const auto& o : orders) {
    ++first[o[0]];
    for (std::size_t i = 1; i < o.size(); ++i) ++follows[{o[i - 1], o[i]}];
  }
  for (const auto& [mode, n] : first) EXPECT_EQ(n, 2) << guidance::modeName(mode);
  EXPECT_EQ(follows.size(), 6u);
  for (const auto& [pair, n] : follows) EXPECT_EQ(n, 2);
}

// A station waiting for subjects other stations hold asks again every quarter of the lease, but
// at least once a second: a subject given back (or the study's end) is seen within a second
// under a long lease too, not 15 minutes later under a lease of an hour.
TEST(StudyDatabase, AWaitingStationAsksAgainEveryQuarterLeaseAtLeastOnceASecond) {
  StudyFolder folder;
  { (void)StudyDatabase::create(folder.dir / "s.sqlite", loadStudy(folder.dir / "study.json")); }
  const auto interval = [&](double lease_s) {
    return StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kReadOnly, {.lease_timeout_s = lease_s})
        .claimRetryInterval_s();
  };
  EXPECT_EQ(interval(2.0), 0.5);
  EXPECT_EQ(interval(30.0), 1.0);
  EXPECT_EQ(interval(3600.0), 1.0);
}

TEST(StudyDatabase, RefusesFilesThatAreNotStudiesOrAreNewer) {
  test::TempDir dir;
  test::writeText(dir / "text.sqlite", "just some text, long enough to not be an empty database file.............");
  EXPECT_THAT([&] { try { (void)StudyDatabase::open(dir / "text.sqlite", OpenMode::kReadOnly); } catch (const InputError& e) { return std::string(e.what()); } return std::string(); }(),
              HasSubstr("not a hattr study database"));

  sqlite3* other = nullptr;
  ASSERT_EQ(sqlite3_open((dir / "other.sqlite").c_str(), &other), SQLITE_OK);
  sqlite3_exec(other, "CREATE TABLE t (x); PRAGMA application_id = 42;", nullptr, nullptr, nullptr);
  sqlite3_close(other);
  try {
    (void)StudyDatabase::open(dir / "other.sqlite", OpenMode::kReadOnly);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("not a hattr study database (SQLite application id 0x2a, expected 0x68617474)"));
  }

  StudyFolder folder;
  { (void)StudyDatabase::create(folder.dir / "s.sqlite", loadStudy(folder.dir / "study.json")); }
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open((folder.dir / "s.sqlite").c_str(), &db), SQLITE_OK);
  sqlite3_exec(db, "PRAGMA user_version = 99", nullptr, nullptr, nullptr);
  sqlite3_close(db);
  try {
    (void)StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kReadWrite);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("study schema version 99 is newer than this build of hattr reads (1 to 5)"));
  }
}

TEST(StudyDatabase, MigratesTheFirstReleasedSchema) {
  StudyFolder folder;
  { (void)StudyDatabase::create(folder.dir / "s.sqlite", loadStudy(folder.dir / "study.json")); }
  // Turn it back into a version-1 file: what 1 -> 2 and 2 -> 3 added goes away.
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open((folder.dir / "s.sqlite").c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db,
                         (std::string(kBackToSchema4) +
                          "DROP TABLE disturbed_attempts; ALTER TABLE trials DROP COLUMN disturbed; DROP TABLE results; "
                         "ALTER TABLE samples DROP COLUMN encoding; "
                          "ALTER TABLE trials DROP COLUMN interruptions; PRAGMA user_version = 1;").c_str(),
                         nullptr, nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(db);
  StudyDatabase reopened = StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kReadWrite);
  EXPECT_EQ(reopened.schemaVersion(), kStudySchemaVersion);
  reopened.putResult("k", "v");
  EXPECT_EQ(reopened.result("k"), "v");
  EXPECT_EQ(reopened.trials().front().interruptions, 0);
  EXPECT_EQ(reopened.trials().front().disturbed, "");
  EXPECT_EQ(reopened.trials().front().disturbed_attempts, 0);
}

TEST(StudyDatabase, ASecondRunnerGetsAClearError) {
  StudyFolder folder;
  { (void)StudyDatabase::create(folder.dir / "s.sqlite", loadStudy(folder.dir / "study.json")); }
  StudyDatabase first = StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kRunner);
  (void)first.beginSession("S01");
  try {
    (void)StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kRunner);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("the study is being run by process"));
  }
  // Readers are welcome meanwhile.
  EXPECT_EQ(StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kReadOnly).trials().size(), 18u);
}

TEST(StudyRunner, RunsTheWholeProtocolAndExportImportIsExact) {
  HATTR_STARTS_NO_THREAD();
  StudyFolder folder;
  StudyDatabase db = StudyDatabase::create(folder.dir / "s.sqlite", loadStudy(folder.dir / "study.json"));
  db = StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kRunner);
  StudyRunner runner(db, makeScriptParticipant);
  EXPECT_EQ(runner.run({}), 18);
  const auto trials = db.trials();
  ASSERT_EQ(trials.size(), 18u);
  for (const auto& t : trials) {
    EXPECT_EQ(t.status, TrialStatus::kCompleted);
    EXPECT_EQ(t.sample_count, 350);  // 0.3 s expert + 0.05 s tail at 1 kHz
  }
  // Recall trials ran without guidance; training trials in guided modes with it.
  const auto& recall = *std::find_if(trials.begin(), trials.end(), [](const TrialRecord& t) {
    return t.plan.phase == kPhaseRecall && t.plan.mode != guidance::TrainingMode::kBasic;
  });
  EXPECT_EQ(db.trialProfile(recall.id).metadata().extra.at("mode"), "BASIC");

  // Export, import into a new database, export again: the same profiles, bit for bit.
  ASSERT_EQ(exportStudy(db, folder.dir / "export1"), 18u);
  ASSERT_EQ(importStudy(folder.dir / "export1", folder.dir / "copy.sqlite"), 18u);
  const StudyDatabase copy = StudyDatabase::open(folder.dir / "copy.sqlite", OpenMode::kReadOnly);
  ASSERT_EQ(exportStudy(copy, folder.dir / "export2"), 18u);
  for (std::size_t i = 0; i < trials.size(); ++i) {
    EXPECT_EQ(copy.trialProfile(copy.trials()[i].id), db.trialProfile(trials[i].id)) << "trial " << i;
  }
  for (const auto& entry : std::filesystem::recursive_directory_iterator(folder.dir / "export1" / "trials")) {
    if (!entry.is_regular_file()) continue;
    const auto relative = std::filesystem::relative(entry.path(), folder.dir / "export1");
    EXPECT_EQ(test::readText(entry.path()), test::readText(folder.dir / "export2" / relative)) << relative;
  }
}

TEST(StudyRunner, StopsAndResumesAtTheFirstUnfinishedTrial) {
  StudyFolder folder;
  { (void)StudyDatabase::create(folder.dir / "s.sqlite", loadStudy(folder.dir / "study.json")); }
  {
    StudyDatabase db = StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kRunner);
    StudyRunner runner(db, makeScriptParticipant);
    EXPECT_EQ(runner.run({.max_trials = 5}), 5);
    // A trial left running, as if the process had died in it.
    db.markRunning(db.nextTrial("S01")->id, db.beginSession("S01"));
  }
  StudyDatabase db = StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kRunner);
  const auto next = db.nextTrial("S01");
  ASSERT_TRUE(next.has_value());
  EXPECT_EQ(next->plan.sequence, 5);
  EXPECT_EQ(next->status, TrialStatus::kInterrupted);
  EXPECT_EQ(next->interruptions, 1);
  StudyRunner runner(db, makeScriptParticipant);
  EXPECT_EQ(runner.run({}), 13);
}

// A process that dies after keeping a disturbed attempt and before its repeat begins left no
// attempt running: the attempts stay 1 + interruptions + disturbed attempts (a station killed
// there had counted an interruption besides: clean-clone run 17).
TEST(StudyDatabase, ADisturbedAttemptKeptLeavesTheTrialPendingNotRunning) {
  StudyFolder folder;
  { (void)StudyDatabase::create(folder.dir / "s.sqlite", loadStudy(folder.dir / "study.json")); }
  {
    StudyDatabase db = StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kRunner);
    const TrialRecord trial = *db.nextTrial("S01");
    db.markRunning(trial.id, db.beginSession("S01"));
    HapticProfile attempt;
    Sample s;
    attempt.append(s);
    db.keepDisturbedAttempt(trial.id, attempt, "1 stall");
    EXPECT_EQ(db.nextTrial("S01")->status, TrialStatus::kPending);
  }  // the process "dies" before the repeat
  StudyDatabase db = StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kRunner);
  const TrialRecord again = *db.nextTrial("S01");
  EXPECT_EQ(again.interruptions, 0);
  EXPECT_EQ(again.disturbed_attempts, 1);
  EXPECT_EQ(again.attempts, again.interruptions + again.disturbed_attempts) << "each attempt so far is one or the other";
}

/// A script participant that counts what the runner asks of it (in `log`).
struct RunnerLog {
  int participants = 0;
  int relived_or_learned = 0;
};
class CountingParticipant : public Participant {
 public:
  CountingParticipant(std::unique_ptr<Participant> inner, RunnerLog& log) : inner_(std::move(inner)), log_(log) {}
  device::HandScript& handForTrial(const TrialPlan& plan) override { return inner_->handForTrial(plan); }
  void trialCompleted(const TrialPlan& plan, const HapticProfile& recorded) override {
    ++log_.relived_or_learned;
    inner_->trialCompleted(plan, recorded);
  }

 private:
  std::unique_ptr<Participant> inner_;
  RunnerLog& log_;
};
ParticipantFactory countingFactory(RunnerLog& log) {
  return [&log](const SubjectRecord& subject, const HapticProfile& expert) {
    ++log.participants;
    return std::make_unique<CountingParticipant>(makeScriptParticipant(subject, expert), log);
  };
}

// A resume costs what is left: a finished subject gets no participant and relives nothing;
// a subject with trials left relives its own completed trials, then runs the rest.
TEST(StudyRunner, AResumeRelivesOnlyTheSubjectsWithTrialsLeft) {
  HATTR_STARTS_NO_THREAD();
  StudyFolder folder(smallStudy(3));
  { (void)StudyDatabase::create(folder.dir / "s.sqlite", loadStudy(folder.dir / "study.json")); }
  StudyDatabase db = StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kRunner);
  RunnerLog first;
  ASSERT_EQ(StudyRunner(db, countingFactory(first)).run({.max_trials = 9 + 4}), 13);  // S01 whole, S02's first 4

  RunnerLog resumed;
  EXPECT_EQ(StudyRunner(db, countingFactory(resumed)).run({}), 5 + 9);
  EXPECT_EQ(resumed.participants, 2);                   // S02 and S03, not S01
  EXPECT_EQ(resumed.relived_or_learned, 4 + 5 + 9);    // S02's 4 relived, then 14 learned

  RunnerLog finished;
  EXPECT_EQ(StudyRunner(db, countingFactory(finished)).run({}), 0);
  EXPECT_EQ(finished.participants, 0);
  EXPECT_EQ(finished.relived_or_learned, 0);
}

// Subjects run at once: one whose participant cannot be made fails the run with its error;
// the others stop after their current trial, and what they completed is kept.
TEST(StudyRunner, SubjectsAtOnceStopWhenOneFailsAndKeepWhatTheyCompleted) {
  StudyFolder folder(smallStudy(4));
  { (void)StudyDatabase::create(folder.dir / "s.sqlite", loadStudy(folder.dir / "study.json")); }
  StudyDatabase db = StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kRunner);
  const auto failing = [](const SubjectRecord& subject, const HapticProfile& expert) {
    if (subject.id == "S02") throw InputError("S02 cannot come today");
    return makeScriptParticipant(subject, expert);
  };
  try {
    (void)StudyRunner(db, failing).run({.subjects_at_once = 2});
    ADD_FAILURE() << "the run did not fail";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("S02 cannot come today"));
  }
  int completed = 0;
  for (const TrialRecord& t : db.trials()) {
    EXPECT_NE(t.status, TrialStatus::kRunning) << t.id;
    if (t.status == TrialStatus::kCompleted) {
      ++completed;
      EXPECT_NE(t.plan.subject, "S02");
      EXPECT_GT(db.trialProfile(t.id).size(), 0u);
    }
  }
  EXPECT_LE(completed, 9);  // S01 at most: no subject is taken up after the failure
  // The rest, one at a time, once S02 can come: every trial completed once.
  EXPECT_EQ(StudyRunner(db, makeScriptParticipant).run({}), 4 * 9 - completed);
}

// A trial list with a gap (an earlier trial pending, later ones completed): the runner runs
// only the pending one; every completed trial keeps its profile, attempts and end time, and
// the database itself refuses to run or replace a completed trial.
TEST(StudyRunner, NeverRunsOrReplacesACompletedTrialWhateverTheGap) {
  StudyFolder folder;
  { (void)StudyDatabase::create(folder.dir / "s.sqlite", loadStudy(folder.dir / "study.json")); }
  std::vector<TrialRecord> before;
  std::vector<HapticProfile> profiles;
  {
    StudyDatabase db = StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kRunner);
    StudyRunner runner(db, makeScriptParticipant);
    ASSERT_EQ(runner.run({.only_subject = "S01"}), 9);
    before = db.trials("S01");
    for (const TrialRecord& t : before) profiles.push_back(db.trialProfile(t.id));
  }
  // The gap: the third trial back to pending, its samples gone.
  sqlite3* raw = nullptr;
  ASSERT_EQ(sqlite3_open((folder.dir / "s.sqlite").c_str(), &raw), SQLITE_OK);
  const std::string gap = fmt::format("UPDATE trials SET status = 'pending' WHERE id = {0}; DELETE FROM samples WHERE trial = {0};",
                                      before[2].id);
  ASSERT_EQ(sqlite3_exec(raw, gap.c_str(), nullptr, nullptr, nullptr), SQLITE_OK);
  sqlite3_close(raw);

  StudyDatabase db = StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kRunner);
  StudyRunner runner(db, makeScriptParticipant);
  EXPECT_EQ(runner.run({.only_subject = "S01"}), 1);
  const std::vector<TrialRecord> after = db.trials("S01");
  ASSERT_EQ(after.size(), before.size());
  for (std::size_t i = 0; i < after.size(); ++i) {
    EXPECT_EQ(after[i].status, TrialStatus::kCompleted) << i;
    EXPECT_EQ(db.trialProfile(after[i].id), profiles[i]) << i;  // the same hand, the same trial
    if (i == 2) continue;
    EXPECT_EQ(after[i].attempts, before[i].attempts) << i;
    EXPECT_EQ(after[i].ended_utc, before[i].ended_utc) << i;
  }
  EXPECT_EQ(after[2].attempts, before[2].attempts + 1);

  // The writer's own guard.
  const std::int64_t done = after[4].id;
  try {
    db.markRunning(done, db.beginSession("S01"));
    FAIL() << "a completed trial was marked running";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr(fmt::format("trial {} is completed or missing; a completed trial is never run again", done)));
    EXPECT_THAT(e.what(), HasSubstr("s.sqlite"));
  }
  try {
    db.completeTrial(done, profiles[0], "ok");
    FAIL() << "a completed trial was replaced";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("a completed trial is never replaced"));
  }
  EXPECT_EQ(db.trialProfile(done), profiles[4]);
  EXPECT_EQ(db.trials("S01")[4].status, TrialStatus::kCompleted);
}

/// The files in `dir` (names only), hidden ones included.
std::set<std::string> filesIn(const std::filesystem::path& dir) {
  std::set<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}

// Import is all or nothing: one bad trial, and no database (nor any hidden half of one) is
// left; with the trial fixed, the same import succeeds.
TEST(StudyImport, OneBadTrialLeavesNoDatabaseBehind) {
  HATTR_STARTS_NO_THREAD();
  StudyFolder folder;
  {
    StudyDatabase db = StudyDatabase::create(folder.dir / "s.sqlite", loadStudy(folder.dir / "study.json"));
    db = StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kRunner);
    StudyRunner runner(db, makeScriptParticipant);
    ASSERT_EQ(runner.run({}), 18);
    ASSERT_EQ(exportStudy(db, folder.dir / "export"), 18u);
  }
  // Damage the 10th trial's file.
  std::filesystem::path victim;
  for (const auto& e : std::filesystem::recursive_directory_iterator(folder.dir / "export" / "trials")) {
    if (e.is_regular_file() && e.path().filename().string().starts_with("001_")) victim = e.path();
  }
  ASSERT_FALSE(victim.empty());
  const std::string good = test::readText(victim);
  test::writeText(victim, good.substr(0, good.size() / 2) + "1.0,not-a-number\n");
  const std::set<std::string> before = filesIn(folder.dir.path());
  try {
    (void)importStudy(folder.dir / "export", folder.dir / "copy.sqlite");
    FAIL() << "a damaged trial was imported";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr(victim.filename().string()));
  }
  EXPECT_EQ(filesIn(folder.dir.path()), before);  // no copy.sqlite, no hidden file, no journal
  test::writeText(victim, good);
  EXPECT_EQ(importStudy(folder.dir / "export", folder.dir / "copy.sqlite"), 18u);
  EXPECT_EQ(StudyDatabase::open(folder.dir / "copy.sqlite", OpenMode::kReadOnly).trials().size(), 18u);
}

// An import's table names each trial's file; one that points outside the export is refused.
TEST(StudyImport, RefusesATrialFileOutsideTheExport) {
  StudyFolder folder;
  {
    StudyDatabase db = StudyDatabase::create(folder.dir / "s.sqlite", loadStudy(folder.dir / "study.json"));
    db = StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kRunner);
    StudyRunner runner(db, makeScriptParticipant);
    ASSERT_EQ(runner.run({.max_trials = 1}), 1);
    ASSERT_EQ(exportStudy(db, folder.dir / "export"), 1u);
  }
  std::string table = test::readText(folder.dir / "export" / "trials.csv");
  const auto at = table.find("trials/S01/");
  ASSERT_NE(at, std::string::npos);
  table.replace(at, std::string("trials/S01/").size(), "../../");
  test::writeText(folder.dir / "export" / "trials.csv", table);
  try {
    (void)importStudy(folder.dir / "export", folder.dir / "copy.sqlite");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("trials.csv:2: file: expected a path inside the export folder, got \"../../"));
  }
  EXPECT_FALSE(std::filesystem::exists(folder.dir / "copy.sqlite"));
}

// Creation is atomic: whatever fails while a database is being made, the file never appears.
TEST(StudyDatabase, CreationIsAllOrNothing) {
  StudyFolder folder;
  const std::set<std::string> before = filesIn(folder.dir.path());
  EXPECT_THROW((void)StudyDatabase::create(folder.dir / "s.sqlite", loadStudy(folder.dir / "study.json"),
                                           [](StudyDatabase&) { throw Error("the disk is full"); }),
               Error);
  EXPECT_EQ(filesIn(folder.dir.path()), before);
  // An existing file is never replaced, even one that appears while the database is made.
  EXPECT_THROW((void)StudyDatabase::create(folder.dir / "s.sqlite", loadStudy(folder.dir / "study.json"),
                                           [&](StudyDatabase&) { test::writeText(folder.dir / "s.sqlite", "mine"); }),
               InputError);
  EXPECT_EQ(test::readText(folder.dir / "s.sqlite"), "mine");
  std::filesystem::remove(folder.dir / "s.sqlite");
  EXPECT_EQ(filesIn(folder.dir.path()), before);
}

// Subject ids and skills become file names: one that could leave a folder is refused where it
// enters (the study file), and the export's writer refuses one that got in some other way.
TEST(StudyDefinition, SubjectIdsAndSkillsThatCouldEscapeAFolderAreRefused) {
  test::TempDir dir;
  writeExpert(dir.path() / "expert.csv");
  const std::string message = studyError(R"({"name": "x", "skill": "../na", "experts": {"../na": "expert.csv"},
      "subjects": [{"id": "../../x"}, {"id": "a/b"}, {"id": ".hidden"}, {"id": "fine-01.b"}]})", dir.path());
  EXPECT_THAT(message, HasSubstr("subject id \"../../x\": expected 1 to 64 letters, digits, '_', '-' or '.', not "
                                 "starting with '.'"));
  EXPECT_THAT(message, HasSubstr("subject id \"a/b\""));
  EXPECT_THAT(message, HasSubstr("subject id \".hidden\""));
  EXPECT_THAT(message, Not(HasSubstr("fine-01.b")));
  EXPECT_THAT(message, HasSubstr("experts: skill \"../na\""));
}

TEST(StudyExport, TheWriterRefusesANameThatWouldLeaveTheFolder) {
  StudyFolder folder;
  { (void)StudyDatabase::create(folder.dir / "s.sqlite", loadStudy(folder.dir / "study.json")); }
  // A database changed behind hattr's back.
  sqlite3* raw = nullptr;
  ASSERT_EQ(sqlite3_open((folder.dir / "s.sqlite").c_str(), &raw), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(raw, "UPDATE trials SET subject = '../../x' WHERE subject = 'S02'; "
                              "UPDATE subjects SET id = '../../x' WHERE id = 'S02';", nullptr, nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(raw);
  const StudyDatabase db = StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kReadOnly);
  try {
    (void)exportStudy(db, folder.dir / "out" / "export");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("study export: subject id \"../../x\""));
    EXPECT_THAT(e.what(), HasSubstr("not written"));
  }
  EXPECT_FALSE(std::filesystem::exists(folder.dir / "out"));
  EXPECT_FALSE(std::filesystem::exists(folder.dir / "x"));
}

// A study stored before the name rule (a subject "P 01") still opens, runs and exports: the
// rule applies to new study files, the export's writer refuses only names that leave a folder.
// The export also takes a folder written with a trailing slash, and an existing empty one.
TEST(StudyExport, AStudyStoredBeforeTheNameRuleOpensAndExports) {
  StudyFolder folder(smallStudy(1));
  { (void)StudyDatabase::create(folder.dir / "s.sqlite", loadStudy(folder.dir / "study.json")); }
  sqlite3* raw = nullptr;
  ASSERT_EQ(sqlite3_open((folder.dir / "s.sqlite").c_str(), &raw), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(raw, "UPDATE trials SET subject = 'P 01'; UPDATE subjects SET id = 'P 01'; "
                              "UPDATE study SET definition = replace(definition, '\"S01\"', '\"P 01\"');",
                         nullptr, nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(raw);
  {
    StudyDatabase db = StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kRunner);
    EXPECT_EQ(db.subjects().front().id, "P 01");
    StudyRunner runner(db, makeScriptParticipant);
    EXPECT_EQ(runner.run({.max_trials = 2}), 2);
  }
  const StudyDatabase db = StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kReadOnly);
  EXPECT_EQ(exportStudy(db, (folder.dir / "exp").string() + "/"), 2u);
  EXPECT_TRUE(std::filesystem::is_directory(folder.dir / "exp" / "trials" / "P 01"));
  EXPECT_TRUE(std::filesystem::is_regular_file(folder.dir / "exp" / "study.json"));
  std::filesystem::create_directory(folder.dir / "empty");
  EXPECT_EQ(exportStudy(db, folder.dir / "empty"), 2u);
  EXPECT_TRUE(std::filesystem::is_regular_file(folder.dir / "empty" / "trials.csv"));
  EXPECT_EQ(filesIn(folder.dir / "empty"), (std::set<std::string>{"experts", "study.json", "trials", "trials.csv"}));
}

// An import's table that lists a trial twice is refused at the line, and leaves no database.
TEST(StudyImport, ATrialListedTwiceIsRefusedAtItsLine) {
  StudyFolder folder;
  {
    StudyDatabase db = StudyDatabase::create(folder.dir / "s.sqlite", loadStudy(folder.dir / "study.json"));
    db = StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kRunner);
    StudyRunner runner(db, makeScriptParticipant);
    ASSERT_EQ(runner.run({.max_trials = 1}), 1);
    ASSERT_EQ(exportStudy(db, folder.dir / "export"), 1u);
  }
  std::string table = test::readText(folder.dir / "export" / "trials.csv");
  const auto second = table.find('\n', table.find('\n') + 1);
  table += table.substr(table.find('\n') + 1, second - table.find('\n'));  // the first trial again
  test::writeText(folder.dir / "export" / "trials.csv", table);
  try {
    (void)importStudy(folder.dir / "export", folder.dir / "copy.sqlite");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("is listed twice (first on line 2)"));
  }
  EXPECT_FALSE(std::filesystem::exists(folder.dir / "copy.sqlite"));
}

// An older schema is brought up to date by a writer; a reader says so instead of failing on a
// missing column.
TEST(StudyDatabase, AnOlderSchemaOpenedForReadingSaysHowToUpdateIt) {
  StudyFolder folder;
  { (void)StudyDatabase::create(folder.dir / "s.sqlite", loadStudy(folder.dir / "study.json")); }
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open((folder.dir / "s.sqlite").c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db,
                         (std::string(kBackToSchema4) + "DROP TABLE disturbed_attempts; ALTER TABLE trials DROP COLUMN "
                          "disturbed; ALTER TABLE samples DROP COLUMN encoding; PRAGMA user_version = 2;").c_str(),
                         nullptr, nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(db);
  try {
    (void)StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kReadOnly);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("study schema version 2 is older than this build's"));
  }
  EXPECT_EQ(StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kReadWrite).schemaVersion(), kStudySchemaVersion);
  EXPECT_NO_THROW((void)StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kReadOnly).trials());
}

TEST(SamplePacking, IsExactLosslessAndWholeStepsAtAResolution) {
  std::mt19937_64 rng(test::testSeed(17));
  for (const RawChannels raw : {RawChannels{}, RawChannels{true, true}}) {
    const HapticProfile p = test::randomProfile(rng, 300, raw);
    EXPECT_EQ(decodeTrialSamples(encodeTrialSamples(p), kCompactSamples, raw, p.size()), p.samples());
    const auto stepped = decodeTrialSamples(encodeTrialSamples(p, io::defaultResolution()), kCompactSamples, raw, p.size());
    ASSERT_EQ(stepped.size(), p.size());
    EXPECT_EQ(stepped[7].p_WT.x(), static_cast<double>(std::llround(p.samples()[7].p_WT.x() / 1e-6)) * 1e-6);
  }
  EXPECT_THROW((void)decodeTrialSamples("short", kCompactSamples, RawChannels{}, 1), InputError);
  EXPECT_THROW((void)decodeTrialSamples("short", kRowSamples, RawChannels{}, 1), InputError);
  // A block's mark and its own revision must agree.
  const HapticProfile p = test::randomProfile(rng, 20, RawChannels{});
  try {
    (void)decodeTrialSamples(encodeTrialSamples(p), kCompactSamplesV1, RawChannels{}, p.size());
    FAIL() << "decoded";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("samples: a block marked hsc1 starts as hsc2 (damaged)"));
  }
  try {
    (void)decodeTrialSamples("", "gzip", RawChannels{}, 0);
    FAIL() << "decoded";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("samples: encoding \"gzip\": expected hsc2, hsc1 or f64-rows"));
  }
}

/// Schema 3's encoding of a profile's samples: one row of little-endian doubles per sample.
std::string rowSamples(const HapticProfile& profile) {
  std::string bytes;
  for (const Sample& s : profile.samples()) {
    for (const auto& info : allChannels()) {
      if (info.derived || needsRawChannel(info.channel, profile.rawChannels())) continue;
      const double v = channelValue(s, info.channel);
      bytes.append(reinterpret_cast<const char*>(&v), sizeof v);
    }
  }
  return bytes;
}

TEST(StudyDatabase, MigratesSchema3InPlaceRewritingEveryStoredTrialCompactlyAndLosslessly) {
  StudyFolder folder;
  std::mt19937_64 rng(test::testSeed(23));
  std::vector<HapticProfile> kept;
  {
    StudyDatabase db = StudyDatabase::create(folder.dir / "s.sqlite", loadStudy(folder.dir / "study.json"));
    db = StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kRunner);
    const auto trials = db.trials("S01");
    const std::int64_t session = db.beginSession("S01");
    for (std::size_t i = 0; i < 3; ++i) {
      kept.push_back(test::randomProfile(rng, 500 + 100 * i, RawChannels{.tilt = i != 1}));
      db.markRunning(trials[i].id, session);
      if (i == 2) db.keepDisturbedAttempt(trials[i].id, kept.back(), "1 stall");
      db.completeTrial(trials[i].id, kept.back(), "ok");
    }
  }
  // Back to schema 3, as it stored samples: rows of doubles, no encoding column.
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open((folder.dir / "s.sqlite").c_str(), &db), SQLITE_OK);
  {
    StudyDatabase reader = StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kReadOnly);
    const auto trials = reader.trials("S01");
    for (std::size_t i = 0; i < 3; ++i) {
      for (const char* sql : {"UPDATE samples SET data = ? WHERE trial = ?", "UPDATE disturbed_attempts SET data = ? WHERE trial = ?"}) {
        sqlite3_stmt* st = nullptr;
        ASSERT_EQ(sqlite3_prepare_v2(db, sql, -1, &st, nullptr), SQLITE_OK);
        const std::string rows = rowSamples(kept[i]);
        sqlite3_bind_blob(st, 1, rows.data(), static_cast<int>(rows.size()), SQLITE_TRANSIENT);
        sqlite3_bind_int64(st, 2, trials[i].id);
        ASSERT_EQ(sqlite3_step(st), SQLITE_DONE);
        sqlite3_finalize(st);
      }
    }
  }
  ASSERT_EQ(sqlite3_exec(db,
                         (std::string(kBackToSchema4) + "ALTER TABLE samples DROP COLUMN encoding; ALTER TABLE "
                          "disturbed_attempts DROP COLUMN encoding; PRAGMA user_version = 3;").c_str(),
                         nullptr, nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(db);

  // Opened for writing, it is brought up to date: every block rewritten, nothing lost.
  StudyDatabase migrated = StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kReadWrite);
  EXPECT_EQ(migrated.schemaVersion(), kStudySchemaVersion);
  const auto trials = migrated.trials("S01");
  for (std::size_t i = 0; i < 3; ++i) {
    const HapticProfile back = migrated.trialProfile(trials[i].id);
    EXPECT_EQ(back.samples(), kept[i].samples()) << "trial " << i;
    EXPECT_EQ(back.rawChannels(), kept[i].rawChannels());
  }
  ASSERT_EQ(sqlite3_open((folder.dir / "s.sqlite").c_str(), &db), SQLITE_OK);
  const auto count = [&](const char* sql) {
    sqlite3_stmt* st = nullptr;
    EXPECT_EQ(sqlite3_prepare_v2(db, sql, -1, &st, nullptr), SQLITE_OK);
    EXPECT_EQ(sqlite3_step(st), SQLITE_ROW);
    const std::int64_t n = sqlite3_column_int64(st, 0);
    sqlite3_finalize(st);
    return n;
  };
  EXPECT_EQ(count("SELECT COUNT(*) FROM samples WHERE encoding = 'hsc2'"), 3);
  EXPECT_EQ(count("SELECT COUNT(*) FROM disturbed_attempts WHERE encoding = 'hsc2'"), 1);
  EXPECT_EQ(count("SELECT COUNT(*) FROM samples WHERE hex(substr(data, 1, 4)) = '48534302'"), 3);  // "HSC\x02"
  sqlite3_close(db);
}

TEST(StudyDatabase, AMigrationLeavesADamagedSchema3BlockAsItWasAndMigratesTheRest) {
  StudyFolder folder;
  std::mt19937_64 rng(test::testSeed(31));
  std::vector<HapticProfile> kept;
  {
    StudyDatabase db = StudyDatabase::create(folder.dir / "s.sqlite", loadStudy(folder.dir / "study.json"));
    db = StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kRunner);
    const auto trials = db.trials("S01");
    const std::int64_t session = db.beginSession("S01");
    for (std::size_t i = 0; i < 2; ++i) {
      kept.push_back(test::randomProfile(rng, 300, RawChannels{.tilt = true}));
      db.markRunning(trials[i].id, session);
      db.completeTrial(trials[i].id, kept.back(), "ok");
    }
  }
  // Schema 3 again; the second trial's rows cut short by 8 bytes.
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open((folder.dir / "s.sqlite").c_str(), &db), SQLITE_OK);
  std::vector<std::int64_t> ids;
  {
    StudyDatabase reader = StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kReadOnly);
    for (const auto& t : reader.trials("S01")) ids.push_back(t.id);
  }
  for (std::size_t i = 0; i < 2; ++i) {
    sqlite3_stmt* st = nullptr;
    ASSERT_EQ(sqlite3_prepare_v2(db, "UPDATE samples SET data = ? WHERE trial = ?", -1, &st, nullptr), SQLITE_OK);
    std::string rows = rowSamples(kept[i]);
    if (i == 1) rows.resize(rows.size() - 8);
    sqlite3_bind_blob(st, 1, rows.data(), static_cast<int>(rows.size()), SQLITE_TRANSIENT);
    sqlite3_bind_int64(st, 2, ids[i]);
    ASSERT_EQ(sqlite3_step(st), SQLITE_DONE);
    sqlite3_finalize(st);
  }
  ASSERT_EQ(sqlite3_exec(db,
                         (std::string(kBackToSchema4) + "ALTER TABLE samples DROP COLUMN encoding; ALTER TABLE "
                          "disturbed_attempts DROP COLUMN encoding; PRAGMA user_version = 3;").c_str(),
                         nullptr, nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(db);

  StudyDatabase migrated = StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kReadWrite);
  EXPECT_EQ(migrated.schemaVersion(), kStudySchemaVersion);
  EXPECT_EQ(migrated.trialProfile(ids[0]).samples(), kept[0].samples());
  try {
    (void)migrated.trialProfile(ids[1]);
    FAIL() << "read a damaged trial";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("is damaged: samples: 47992 bytes stored, expected 300 samples"));
  }
}

TEST(StudyDatabase, ATrialWhoseTimesAResolutionWouldMergeIsStoredLosslessly) {
  std::string definition = smallStudy();
  definition.insert(definition.rfind('}'), R"(, "storage": {"resolution": {"t": 0.01}})");
  StudyFolder folder(definition);
  StudyDatabase db = StudyDatabase::create(folder.dir / "s.sqlite", loadStudy(folder.dir / "study.json"));
  db = StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kRunner);
  std::mt19937_64 rng(test::testSeed(37));
  const HapticProfile p = test::randomProfile(rng, 200, RawChannels{.tilt = true});  // samples 1 ms apart
  const auto trial = db.trials("S01").front();
  db.markRunning(trial.id, db.beginSession("S01"));
  db.completeTrial(trial.id, p, "ok");
  EXPECT_EQ(db.trialProfile(trial.id).samples(), p.samples());
}

TEST(StudyDatabase, AStudyWithADeclaredResolutionStoresItsTrialsInWholeSteps) {
  std::string definition = smallStudy();
  definition.insert(definition.rfind('}'), R"(, "storage": {"resolution": {"x": 1e-5}})");
  StudyFolder folder(definition);
  StudyDatabase db = StudyDatabase::create(folder.dir / "s.sqlite", loadStudy(folder.dir / "study.json"));
  db = StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kRunner);
  EXPECT_EQ(db.study().resolution.at(Channel::kX), 1e-5);
  EXPECT_EQ(db.study().resolution.at(Channel::kY), 1e-6);  // the default's
  std::mt19937_64 rng(test::testSeed(29));
  const HapticProfile p = test::randomProfile(rng, 400, RawChannels{.tilt = true});
  const auto trial = db.trials("S01").front();
  db.markRunning(trial.id, db.beginSession("S01"));
  db.completeTrial(trial.id, p, "ok");
  const HapticProfile back = db.trialProfile(trial.id);
  for (std::size_t i = 0; i < p.size(); ++i) {
    ASSERT_EQ(back.samples()[i].p_WT.x(), static_cast<double>(std::llround(p.samples()[i].p_WT.x() / 1e-5)) * 1e-5);
  }
  EXPECT_THAT(studyError(R"({"name": "x", "skill": "na", "experts": {"na": "e.csv"}, "modes": ["basic"],
      "protocol": {"training_trials": 1, "recall_trials": 2}, "subjects": {"count": 1},
      "storage": {"resolution": {"x": -1}, "codec": "gzip"}})", folder.dir.path()),
              AllOf(HasSubstr("storage.resolution: \"x\": expected a step > 0 in m, got -1"),
                    HasSubstr("storage: unknown key \"codec\": expected resolution")));
}

}  // namespace
}  // namespace hattr::session
