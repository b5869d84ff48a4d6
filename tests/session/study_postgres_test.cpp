// The study store on PostgreSQL, against a throwaway server this program starts: the same
// study as on SQLite to the bit, stations' subject leases, addresses with passwords refused,
// and `study push` from a station's SQLite file.

#include <chrono>
#include <thread>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/session/study_export.hpp"
#include "hattr/session/study_runner.hpp"
#include "session/study_fixture.hpp"
#include "support/postgres_cluster.hpp"
#include "support/test_support.hpp"

namespace hattr::session {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::Not;

/// A short expert profile (0.3 s) and a study of `subjects` subjects, 6 trials each, in `dir`.
void writeStudy(const test::TempDir& dir, int subjects, double jitter_mm = 1.0) {
  writeExpert(dir / "expert.csv");
  test::writeText(dir / "study.json",
                  fmt::format(R"({{"name": "stations", "skill": "dash", "experts": {{"dash": "expert.csv"}},
    "modes": ["basic", "pcontrol", "alpha"],
    "protocol": {{"training_trials": 1, "recall_trials": 1, "rest_s": 0, "tail_s": 0.05}},
    "world": {{"relief": {{"kind": "flat"}}}},
    "subjects": {{"count": {}, "participant": "script", "options": {{"jitter_mm": {}}}}}}})",
                              subjects, jitter_mm));
}

/// The database name of a test address (postgresql:///NAME?...).
std::string databaseName(const std::string& address) {
  const auto start = std::string("postgresql:///").size();
  return address.substr(start, address.find('?') - start);
}

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(no error)";
}

// A PostgreSQL study of schema 4 (before designs) is refused for reading and brought up to
// date by a writer: each trial's place in the design filled in, its trials kept.
TEST(StudyPostgres, ASchema4StudyIsMigratedByAWriter) {
  test::TempDir dir;
  writeStudy(dir, 2);
  const std::string address = test::PostgresCluster::shared().createDatabase("schema4");
  {
    StudyDatabase db = StudyDatabase::create(address, loadStudy(dir / "study.json"));
    db = StudyDatabase::open(address, OpenMode::kRunner);
    EXPECT_EQ(StudyRunner(db, makeScriptParticipant).run({.max_trials = 4}), 4);
  }
  test::PostgresCluster::shared().sql(databaseName(address),
                                      std::string(kBackToSchema4) + "UPDATE hattr_meta SET schema_version = 4;");
  EXPECT_THAT(errorOf([&] { (void)StudyDatabase::open(address, OpenMode::kReadOnly); }),
              HasSubstr("study schema version 4 is older than this build's 5"));
  StudyDatabase db = StudyDatabase::open(address, OpenMode::kReadWrite);
  EXPECT_EQ(db.schemaVersion(), kStudySchemaVersion);
  const auto trials = db.trials("S02");
  ASSERT_EQ(trials.size(), 6u);
  EXPECT_EQ(trials[3].plan.block, 3) << "the second mode's recall block";
  EXPECT_EQ(trials[3].plan.skill, "dash");
  EXPECT_EQ(db.subjects()[0].spec.group, "all");
  EXPECT_EQ(db.trials("S01")[3].status, TrialStatus::kCompleted);
  EXPECT_NO_THROW((void)StudyDatabase::open(address, OpenMode::kReadOnly).trials());
}

TEST(StudyPostgres, RunsAStudyAsSqliteDoesToTheBit) {
  test::TempDir dir;
  writeStudy(dir, 2);
  const std::string address = test::PostgresCluster::shared().createDatabase("same");
  const StudyDefinition study = loadStudy(dir / "study.json");
  (void)StudyDatabase::create(dir / "s.sqlite", study);
  (void)StudyDatabase::create(address, study);
  for (const std::string& where : {(dir / "s.sqlite").string(), address}) {
    StudyDatabase db = StudyDatabase::open(where, OpenMode::kRunner);
    StudyRunner runner(db, makeScriptParticipant);
    EXPECT_EQ(runner.run({}), 12) << where;
  }
  const StudyDatabase lite = StudyDatabase::open(dir / "s.sqlite", OpenMode::kReadOnly);
  StudyDatabase pg = StudyDatabase::open(address, OpenMode::kReadWrite);
  EXPECT_TRUE(pg.onPostgres());
  EXPECT_EQ(pg.schemaVersion(), kStudySchemaVersion);
  EXPECT_EQ(pg.study().name, "stations");
  EXPECT_EQ(pg.expert("dash"), lite.expert("dash"));
  ASSERT_EQ(pg.subjects().size(), 2u);
  EXPECT_EQ(pg.subjects()[1].mode_order, lite.subjects()[1].mode_order);
  const auto a = lite.trials(), b = pg.trials();
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(b[i].status, TrialStatus::kCompleted);
    EXPECT_EQ(b[i].plan.sequence, a[i].plan.sequence);
    EXPECT_EQ(b[i].sample_count, a[i].sample_count);
    EXPECT_EQ(pg.trialProfile(b[i].id), lite.trialProfile(a[i].id)) << "trial " << i;
  }
  EXPECT_FALSE(pg.runnerActive());  // the stations gave their subjects back
  pg.putResult("k", "v1");
  pg.putResult("k", "v2");
  EXPECT_EQ(pg.result("k"), "v2");
  EXPECT_EQ(pg.result("none"), std::nullopt);

  // A database that already holds a study is not overwritten; one that holds none is named.
  EXPECT_THAT(errorOf([&] { (void)StudyDatabase::create(address, study); }), HasSubstr("already holds a hattr study"));
  const std::string empty = test::PostgresCluster::shared().createDatabase("empty");
  EXPECT_THAT(errorOf([&] { (void)StudyDatabase::open(empty, OpenMode::kReadOnly); }),
              AllOf(HasSubstr("holds no hattr study"), HasSubstr("hattr study init")));
  // A reader cannot write.
  StudyDatabase reader = StudyDatabase::open(address, OpenMode::kReadOnly);
  EXPECT_THROW(reader.putResult("k", "v3"), Error);
}

TEST(StudyPostgres, AddressesWithAPasswordOrMalformedAreRefusedBeforeConnecting) {
  const std::string with_password = "postgresql://lab:s3cret@/study?host=/nonexistent";
  try {
    (void)StudyDatabase::open(with_password, OpenMode::kReadOnly);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("carries a password"), HasSubstr(".pgpass"), Not(HasSubstr("s3cret"))));
  }
  EXPECT_THAT(errorOf([] { (void)StudyDatabase::open("postgresql:///db?password=x&host=/nonexistent", OpenMode::kReadOnly); }),
              HasSubstr("carries a password"));
  EXPECT_THROW((void)StudyDatabase::open("postgresql://host/db?colour=red", OpenMode::kReadOnly), InputError);
  // A malformed address is named in the error, with its password masked.
  EXPECT_THAT(errorOf([] { (void)StudyDatabase::open("postgresql://lab:s3cret@host/db?colour=red", OpenMode::kReadOnly); }),
              AllOf(HasSubstr("postgresql://lab:***@host/db?colour=red"), Not(HasSubstr("s3cret"))));
  EXPECT_THAT(errorOf([] { (void)StudyDatabase::open("postgresql://host/db?password=s3cret&colour=red", OpenMode::kReadOnly); }),
              AllOf(HasSubstr("password=***&colour=red"), Not(HasSubstr("s3cret"))));
  // libpq's reason would quote the malformed part, here the password itself: not shown.
  EXPECT_THAT(errorOf([] { (void)StudyDatabase::open("postgresql://lab:s3%zzcret@host/db", OpenMode::kReadOnly); }),
              AllOf(HasSubstr("lab:***@host"), Not(HasSubstr("zzcret"))));
  // A server that is not there is not bad input: a runtime error naming the address.
  try {
    (void)StudyDatabase::open("postgresql:///study?host=/nonexistent-hattr", OpenMode::kReadOnly);
    FAIL() << "expected Error";
  } catch (const InputError&) {
    FAIL() << "a server that cannot be reached is not an input error";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("postgresql:///study?host=/nonexistent-hattr"), HasSubstr("cannot connect")));
  }
}

TEST(StudyPostgres, AStationHoldsItsSubjectUntilItsLeaseLapsesThenItsRunningTrialIsInterrupted) {
  test::TempDir dir;
  writeStudy(dir, 2);
  const std::string address = test::PostgresCluster::shared().createDatabase("lease");
  (void)StudyDatabase::create(address, loadStudy(dir / "study.json"));
  const StoreOptions lease{.lease_timeout_s = 3.0};

  // A station that dies mid-trial: it claimed S01 and marked a trial running, and then nothing
  // renews its lease (played here by handing the lease to a station id that no process has).
  StudyDatabase dying = StudyDatabase::open(address, OpenMode::kRunner, lease);
  ASSERT_TRUE(dying.claimSubject("S01").granted);
  dying.markRunning(dying.trials("S01").front().id, dying.beginSession("S01"));
  test::PostgresCluster::shared().sql(databaseName(address),
                                      "UPDATE subject_leases SET station = 'gone', host = 'host-x', pid = 4343");

  StudyDatabase other = StudyDatabase::open(address, OpenMode::kRunner, lease);
  const SubjectClaim refused = other.claimSubject("S01");
  EXPECT_FALSE(refused.granted);
  EXPECT_THAT(refused.holder, AllOf(HasSubstr("process 4343 on host-x"), HasSubstr("lease for")));
  EXPECT_TRUE(other.claimSubject("S02").granted);  // another subject is free
  EXPECT_EQ(other.trials("S01").front().status, TrialStatus::kRunning);
  EXPECT_TRUE(other.runnerActive());

  // After the timeout the subject is taken over, and the dead station's trial is interrupted.
  std::this_thread::sleep_for(std::chrono::milliseconds(3300));
  EXPECT_TRUE(other.claimSubject("S01").granted);
  const TrialRecord first = other.trials("S01").front();
  EXPECT_EQ(first.status, TrialStatus::kInterrupted);
  EXPECT_EQ(first.interruptions, 1);

  // A station keeps its subjects while it lives: its leases are renewed (every third of a 3 s
  // timeout here, so only a stall of 3 s could lose one) past the timeout. Given back, a subject
  // is free at once.
  other.releaseSubject("S02");
  StudyDatabase keeper = StudyDatabase::open(address, OpenMode::kRunner, {.lease_timeout_s = 3.0});
  ASSERT_TRUE(keeper.claimSubject("S02").granted);
  std::this_thread::sleep_for(std::chrono::milliseconds(4000));
  EXPECT_FALSE(other.claimSubject("S02").granted);
  keeper.releaseSubject("S02");
  EXPECT_TRUE(other.claimSubject("S02").granted);
}

TEST(StudyPostgres, AStationWhoseSubjectWasTakenOverStoresNothingMore) {
  test::TempDir dir;
  writeStudy(dir, 1);
  const std::string address = test::PostgresCluster::shared().createDatabase("takeover");
  (void)StudyDatabase::create(address, loadStudy(dir / "study.json"));
  StudyDatabase station = StudyDatabase::open(address, OpenMode::kRunner);
  ASSERT_TRUE(station.claimSubject("S01").granted);
  const std::int64_t session = station.beginSession("S01");
  const TrialRecord trial = station.trials("S01").front();
  station.markRunning(trial.id, session);

  // Another station takes S01 over (this one's lease lapsed while it was stalled).
  test::PostgresCluster::shared().sql(databaseName(address),
                                      "UPDATE subject_leases SET station = 'elsewhere', host = 'host-b', pid = 4242");
  HapticProfile profile({.subject = "S01", .skill = "dash", .nominal_rate_hz = 1000.0});
  profile.append(Sample{});
  const std::string message = errorOf([&] { station.completeTrial(trial.id, profile, "ok"); });
  EXPECT_THAT(message, AllOf(HasSubstr("S01 is no longer this station's"), HasSubstr("process 4242 on host-b")));
  EXPECT_THROW(station.keepDisturbedAttempt(trial.id, profile, "stall"), SubjectTakenOver);
  EXPECT_THROW(station.markRunning(trial.id, session), SubjectTakenOver);
  EXPECT_THROW(station.completeTrial(trial.id, profile, "ok"), SubjectTakenOver);
  // A device failure now is not hidden by the lost lease: the taker interrupts the trial.
  EXPECT_NO_THROW(station.failTrial(trial.id, "device fault"));
  const TrialRecord after = station.trials("S01").front();
  EXPECT_EQ(after.status, TrialStatus::kRunning);
  EXPECT_EQ(after.sample_count, 0);
  EXPECT_EQ(after.disturbed_attempts, 0);
}

TEST(StudyPostgres, PushCopiesAStationsTrialsOnceAndRefusesConflictsWritingNothing) {
  test::TempDir dir;
  writeStudy(dir, 2);
  const StudyDefinition study = loadStudy(dir / "study.json");
  const std::string address = test::PostgresCluster::shared().createDatabase("push");
  (void)StudyDatabase::create(address, study);

  // A station ran S01 whole and 2 trials of S02 offline, on SQLite.
  (void)StudyDatabase::create(dir / "station.sqlite", study);
  {
    StudyDatabase db = StudyDatabase::open(dir / "station.sqlite", OpenMode::kRunner);
    StudyRunner runner(db, makeScriptParticipant);
    EXPECT_EQ(runner.run({.only_subject = "S01"}), 6);
    EXPECT_EQ(runner.run({.only_subject = "S02", .max_trials = 2}), 2);
  }
  const StudyDatabase station = StudyDatabase::open(dir / "station.sqlite", OpenMode::kReadOnly);
  StudyDatabase lab = StudyDatabase::open(address, OpenMode::kReadWrite);
  const auto first = lab.pushFrom(station);
  EXPECT_EQ(first.pushed, 8);
  EXPECT_EQ(first.subjects, 2);
  EXPECT_EQ(first.already_there, 0);
  const auto again = lab.pushFrom(station);  // idempotent
  EXPECT_EQ(again.pushed, 0);
  EXPECT_EQ(again.already_there, 8);
  const auto a = station.trials(), b = lab.trials();
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(b[i].status, a[i].status) << "trial " << i;
    EXPECT_EQ(b[i].attempts, a[i].attempts);
    if (a[i].status == TrialStatus::kCompleted) {
      EXPECT_EQ(lab.trialProfile(b[i].id), station.trialProfile(a[i].id));
    }
  }

  // The lab finishes S02 on its server; the station, offline, ran S02's third trial
  // differently: that push is refused and writes nothing.
  {
    StudyDatabase runner_db = StudyDatabase::open(address, OpenMode::kRunner);
    StudyRunner runner(runner_db, makeScriptParticipant);
    EXPECT_EQ(runner.run({}), 4);
  }
  test::TempDir other_dir;
  writeStudy(other_dir, 2);
  (void)StudyDatabase::create(dir / "other.sqlite", study);
  {
    StudyDatabase db = StudyDatabase::open(dir / "other.sqlite", OpenMode::kRunner);
    StudyRunner runner(db, [](const SubjectRecord& s, const HapticProfile& expert) {
      SubjectRecord shifted = s;
      shifted.spec.seed += 17;  // another hand on the day
      return makeScriptParticipant(shifted, expert);
    });
    EXPECT_EQ(runner.run({.only_subject = "S02"}), 6);
  }
  const StudyDatabase other = StudyDatabase::open(dir / "other.sqlite", OpenMode::kReadOnly);
  const std::string refused = errorOf([&] { (void)lab.pushFrom(other); });
  EXPECT_THAT(refused, AllOf(HasSubstr("refused, nothing written"), HasSubstr("subject S02 trial 1: completed in both, differently")));
  EXPECT_EQ(lab.pushFrom(station).already_there, 8);

  // Another study altogether is refused whole.
  writeStudy(other_dir, 3);
  (void)StudyDatabase::create(dir / "bigger.sqlite", loadStudy(other_dir / "study.json"));
  const StudyDatabase bigger = StudyDatabase::open(dir / "bigger.sqlite", OpenMode::kReadOnly);
  EXPECT_THAT(errorOf([&] { (void)lab.pushFrom(bigger); }), AllOf(HasSubstr("not the same study"), HasSubstr("subjects")));
}

TEST(StudyPostgres, PushIntoASubjectAStationIsRunningIsRefused) {
  test::TempDir dir;
  writeStudy(dir, 1);
  const StudyDefinition study = loadStudy(dir / "study.json");
  const std::string address = test::PostgresCluster::shared().createDatabase("pushlease");
  (void)StudyDatabase::create(address, study);
  (void)StudyDatabase::create(dir / "station.sqlite", study);
  {
    StudyDatabase db = StudyDatabase::open(dir / "station.sqlite", OpenMode::kRunner);
    StudyRunner runner(db, makeScriptParticipant);
    EXPECT_EQ(runner.run({.max_trials = 1}), 1);
  }
  StudyDatabase station = StudyDatabase::open(address, OpenMode::kRunner);
  ASSERT_TRUE(station.claimSubject("S01").granted);
  StudyDatabase lab = StudyDatabase::open(address, OpenMode::kReadWrite);
  const StudyDatabase offline = StudyDatabase::open(dir / "station.sqlite", OpenMode::kReadOnly);
  EXPECT_THAT(errorOf([&] { (void)lab.pushFrom(offline); }), HasSubstr("is running this subject now"));
  station.releaseSubject("S01");
  EXPECT_EQ(lab.pushFrom(offline).pushed, 1);
}

}  // namespace
}  // namespace hattr::session

namespace hattr::session {
namespace {

TEST(StudyPostgres, ATrialTheStoreRefusesIsKeptInAFileAndRunsAgainTheSame) {
  test::TempDir dir;
  writeStudy(dir, 1);
  const std::string address = test::PostgresCluster::shared().createDatabase("rescue");
  (void)StudyDatabase::create(address, loadStudy(dir / "study.json"));
  // The server refuses every trial's samples (as a full disk would).
  test::PostgresCluster::shared().sql(databaseName(address),
                                      "ALTER TABLE samples ADD CONSTRAINT refuse_all CHECK (sample_count < 0) NOT VALID");
  StudyDatabase db = StudyDatabase::open(address, OpenMode::kRunner);
  StudyRunner runner(db, makeScriptParticipant);
  const std::string error = errorOf([&] { (void)runner.run({.max_trials = 1, .rescue_folder = dir / "rescue"}); });
  EXPECT_THAT(error, AllOf(HasSubstr("refuse_all"), HasSubstr("subject S01's BASIC training trial 1 (sequence 0) was not stored"),
                           HasSubstr("kept in " + (dir / "rescue" / "trials" / "S01").string())));
  std::vector<std::filesystem::path> rescued;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir / "rescue")) {
    if (entry.is_regular_file()) rescued.push_back(entry.path());
  }
  ASSERT_EQ(rescued.size(), 1u);
  const TrialRecord first = db.trials("S01").front();
  EXPECT_NE(first.status, TrialStatus::kCompleted);
  EXPECT_EQ(first.sample_count, 0);

  // With the store back, the trial runs again: the same recording as the one kept.
  test::PostgresCluster::shared().sql(databaseName(address), "ALTER TABLE samples DROP CONSTRAINT refuse_all");
  EXPECT_EQ(runner.run({.max_trials = 1, .rescue_folder = dir / "rescue"}), 1);
  const TrialRecord again = db.trials("S01").front();
  EXPECT_EQ(again.status, TrialStatus::kCompleted);
  EXPECT_EQ(again.interruptions, 1);
  EXPECT_EQ(db.trialProfile(again.id), io::readProfileCsv(rescued.front()));
}

}  // namespace
}  // namespace hattr::session
