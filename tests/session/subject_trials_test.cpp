// The protocol of one subject's trials, stepped (session::SubjectTrials): what StudyRunner and
// the studio's study session both follow. Each trial's result is built here, so every ending
// (stored, disturbed and repeated, failed, refused by the store) is reached on purpose.

#include <sqlite3.h>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/guidance/strategy_catalog.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/session/study_runner.hpp"
#include "hattr/session/subject_trials.hpp"
#include "session/study_fixture.hpp"
#include "support/test_support.hpp"

namespace hattr::session {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

/// One subject, BASIC and ALPHA, two training and one recall trial each: six trials.
struct OneSubjectStudy {
  explicit OneSubjectStudy(const std::string& protocol_extra = "") {
    writeExpert(dir / "expert.csv");
    test::writeText(dir / "study.json",
                    fmt::format(R"({{"name": "steps", "skill": "dash", "experts": {{"dash": "expert.csv"}},
      "modes": ["basic", "alpha"],
      "protocol": {{"training_trials": 2, "recall_trials": 1, "rest_s": 0, "tail_s": 0.05{}}},
      "world": {{"relief": {{"kind": "flat"}}}},
      "subjects": {{"count": 1, "participant": "script"}}}})",
                                protocol_extra));
    (void)StudyDatabase::create(file(), loadStudy(dir / "study.json"));
  }
  [[nodiscard]] std::filesystem::path file() const { return dir / "s.sqlite"; }
  /// Runs SQL on the closed database file.
  void sql(const std::string& statements) const {
    sqlite3* raw = nullptr;
    ASSERT_EQ(sqlite3_open(file().c_str(), &raw), SQLITE_OK);
    ASSERT_EQ(sqlite3_exec(raw, statements.c_str(), nullptr, nullptr, nullptr), SQLITE_OK) << sqlite3_errmsg(raw);
    sqlite3_close(raw);
  }
  test::TempDir dir;
};

/// The steps of S01 in `db`, with the study's references.
SubjectTrials stepsOf(StudyDatabase& db) {
  return SubjectTrials(db.study(), db.subjects().front(), db.trials("S01"), studyReferences(db));
}

/// A clean trial's result: the expert's own samples.
TrialResult cleanResult(StudyDatabase& db) {
  TrialResult result;
  result.profile = db.expert("dash");
  result.profile.metadata().created_utc = "2026-01-01T00:00:00Z";
  return result;
}

/// A trial's result that the loop disturbed with `stalls` stalls.
TrialResult stalledResult(StudyDatabase& db, std::uint64_t stalls) {
  TrialResult result = cleanResult(db);
  result.stalls = stalls;
  return result;
}

TEST(SubjectTrials, PassesCompletedTrialsInOrderAndRestsBeforeEveryTrialButTheFirst) {
  OneSubjectStudy study;
  StudyDatabase db = StudyDatabase::open(study.file(), OpenMode::kRunner);
  const std::vector<TrialRecord> all = db.trials("S01");
  ASSERT_EQ(all.size(), 6u);
  SubjectTrials fresh = stepsOf(db);
  EXPECT_TRUE(fresh.passCompleted().empty());
  EXPECT_FALSE(fresh.restBefore());
  EXPECT_EQ(fresh.current()->id, all[0].id);
  EXPECT_EQ(fresh.prompt(), fmt::format("Training with {}: trial 1 of 2", guidance::modeName(all[0].plan.mode)));
  EXPECT_EQ(fresh.prompt(SubjectTrials::Wording::kPlain),
            fmt::format("Training with {}: trial 1 of 2", guidance::strategyInfo(all[0].plan.mode).plain_name));

  // Trials 0, 1 and 3 done (3 after a gap): the steps pass 0 and 1, run 2, then pass 3.
  const std::int64_t session = db.beginSession("S01");
  for (const int i : {0, 1, 3}) {
    db.markRunning(all[static_cast<std::size_t>(i)].id, session);
    db.completeTrial(all[static_cast<std::size_t>(i)].id, db.expert("dash"), "ok");
  }
  SubjectTrials steps = stepsOf(db);
  EXPECT_EQ(steps.completedCount(), 3);
  const std::vector<TrialRecord> resumed = steps.passCompleted();
  ASSERT_EQ(resumed.size(), 2u);
  EXPECT_EQ(resumed[0].id, all[0].id);
  EXPECT_EQ(resumed[1].id, all[1].id);
  EXPECT_EQ(steps.position(), 2u);
  EXPECT_TRUE(steps.restBefore());
  EXPECT_EQ(steps.prompt(), fmt::format("Recall with {}: trial 1 of 1", guidance::modeName(all[2].plan.mode)));

  steps.begin(db, session);
  TrialResult result = cleanResult(db);
  const SubjectTrials::Outcome outcome = steps.end(db, result, {});
  EXPECT_EQ(outcome.ending, SubjectTrials::Ending::kStored);
  EXPECT_EQ(outcome.trial.id, all[2].id);
  EXPECT_EQ(outcome.trial.status, TrialStatus::kCompleted);
  EXPECT_EQ(result.profile.metadata().created_utc, "");  // nothing that depends on when it ran
  EXPECT_EQ(db.trials("S01")[2].outcome, fmt::format("ok: {} samples, 0 missed, 0 faults", result.profile.size()));
  const std::vector<TrialRecord> gap = steps.passCompleted();
  ASSERT_EQ(gap.size(), 1u);
  EXPECT_EQ(gap[0].id, all[3].id);
  EXPECT_EQ(steps.current()->id, all[4].id);
  EXPECT_EQ(steps.completedCount(), 4);
}

TEST(SubjectTrials, ADisturbedTrialIsKeptAndRunAgainUntilThePolicyStoresIt) {
  OneSubjectStudy study(R"(, "disturbed_trials": "repeat", "max_repeats": 1)");
  StudyDatabase db = StudyDatabase::open(study.file(), OpenMode::kRunner);
  SubjectTrials steps = stepsOf(db);
  const std::int64_t session = db.beginSession("S01");
  const TrialRecord first = *steps.current();
  const SubjectSpec spec = db.subjects().front().spec;
  EXPECT_EQ(steps.setup(Clock::kRealTime, nullptr).live_seed, studyLiveSeed(spec, first.plan, 0));

  steps.begin(db, session);
  TrialResult stalled = stalledResult(db, 1);
  const SubjectTrials::Outcome again = steps.end(db, stalled, {});
  EXPECT_EQ(again.ending, SubjectTrials::Ending::kRepeat);
  EXPECT_EQ(again.disturbed, "1 stall (force zeroed)");
  EXPECT_EQ(steps.attempt(), 1);
  EXPECT_EQ(steps.current()->id, first.id);  // the same trial again
  EXPECT_EQ(steps.setup(Clock::kRealTime, nullptr).live_seed, studyLiveSeed(spec, first.plan, 1));
  EXPECT_EQ(db.trials("S01")[0].disturbed_attempts, 1);
  EXPECT_NE(db.trials("S01")[0].status, TrialStatus::kCompleted);

  // Repeated once already (max_repeats 1): the next disturbed attempt is stored, flagged.
  steps.begin(db, session);
  TrialResult stalled_again = stalledResult(db, 2);
  const SubjectTrials::Outcome stored = steps.end(db, stalled_again, {});
  EXPECT_EQ(stored.ending, SubjectTrials::Ending::kStored);
  EXPECT_EQ(stored.disturbed, "2 stalls (force zeroed)");
  EXPECT_EQ(steps.attempt(), 0);
  const TrialRecord kept = db.trials("S01")[0];
  EXPECT_EQ(kept.status, TrialStatus::kCompleted);
  EXPECT_EQ(kept.disturbed, "2 stalls (force zeroed)");
  EXPECT_THAT(kept.outcome, HasSubstr("; disturbed"));
  EXPECT_EQ(db.trialProfile(kept.id).metadata().extra.at("loop_stalls"), "2");
}

TEST(SubjectTrials, AFailedTrialIsMarkedFailedNothingIsStoredAndItRunsAgainFromAttemptZero) {
  OneSubjectStudy study(R"(, "disturbed_trials": "repeat", "max_repeats": 2)");
  StudyDatabase db = StudyDatabase::open(study.file(), OpenMode::kRunner);
  SubjectTrials steps = stepsOf(db);
  const std::int64_t session = db.beginSession("S01");
  steps.begin(db, session);
  TrialResult stalled = stalledResult(db, 1);
  ASSERT_EQ(steps.end(db, stalled, {}).ending, SubjectTrials::Ending::kRepeat);
  ASSERT_EQ(steps.attempt(), 1);

  steps.begin(db, session);
  TrialResult broken = cleanResult(db);
  broken.failure = "the device stopped answering";
  const SubjectTrials::Outcome outcome = steps.end(db, broken, {});
  EXPECT_EQ(outcome.ending, SubjectTrials::Ending::kFailed);
  EXPECT_EQ(steps.attempt(), 0);
  EXPECT_EQ(steps.position(), 0u);
  const TrialRecord marked = db.trials("S01")[0];
  EXPECT_EQ(marked.status, TrialStatus::kInterrupted);
  EXPECT_EQ(marked.outcome, "failed: the device stopped answering");
  EXPECT_EQ(marked.sample_count, 0);
}

TEST(SubjectTrials, AnEmptyRecordingIsRefusedAndTheTrialStaysToRunAgain) {
  OneSubjectStudy study;
  StudyDatabase db = StudyDatabase::open(study.file(), OpenMode::kRunner);
  SubjectTrials steps = stepsOf(db);
  steps.begin(db, db.beginSession("S01"));
  TrialResult empty;
  try {
    (void)steps.end(db, empty, {});
    FAIL() << "an empty recording was accepted";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("the trial recorded no samples; it stays to be run again"));
  }
  EXPECT_EQ(steps.position(), 0u);
  EXPECT_EQ(db.trials("S01")[0].status, TrialStatus::kRunning);
}

TEST(SubjectTrials, ARecordingTheStoreRefusesIsKeptInTheRescueFolderAndTheTrialStays) {
  OneSubjectStudy study;
  // The store refuses every trial's samples, as a full disk would.
  study.sql("CREATE TRIGGER refuse_all BEFORE INSERT ON samples BEGIN SELECT RAISE(ABORT, 'refuse_all'); END;");
  StudyDatabase db = StudyDatabase::open(study.file(), OpenMode::kRunner);
  SubjectTrials steps = stepsOf(db);
  steps.begin(db, db.beginSession("S01"));
  TrialResult result = cleanResult(db);
  const std::filesystem::path rescue = defaultRescueFolder(db);
  EXPECT_EQ(rescue, std::filesystem::path(study.file().string() + ".unstored"));
  try {
    (void)steps.end(db, result, {});
    FAIL() << "the refused store was not reported";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), AllOf(HasSubstr("refuse_all"), HasSubstr("was not stored: its recording is kept in " +
                                                                   (rescue / "trials" / "S01").string())));
  }
  std::vector<std::filesystem::path> kept;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(rescue)) {
    if (entry.is_regular_file()) kept.push_back(entry.path());
  }
  ASSERT_EQ(kept.size(), 1u);
  EXPECT_EQ(io::readProfileCsv(kept.front()), result.profile);
  EXPECT_EQ(steps.position(), 0u);
  EXPECT_EQ(steps.completedCount(), 0);
  EXPECT_EQ(db.trials("S01")[0].status, TrialStatus::kRunning);
}

}  // namespace
}  // namespace hattr::session
