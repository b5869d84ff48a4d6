#include <sqlite3.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/session/study_export.hpp"
#include "hattr/session/study_runner.hpp"
#include "support/test_support.hpp"

namespace hattr::session {
namespace {

using ::testing::HasSubstr;

/// A short expert profile (0.3 s, pressing 1.2 N) written to `file`.
void writeExpert(const std::filesystem::path& file) {
  HapticProfile p({.subject = "expert", .skill = "dash", .nominal_rate_hz = 100.0});
  for (int i = 0; i <= 30; ++i) {
    Sample s;
    s.t_s = i * 0.01;
    s.p_WT = Vec3(0.001 * i, 0.0, 0.0);
    s.v_WT = Vec3(0.1, 0.0, 0.0);
    s.f_user_W = Vec3(0.0, 0.0, -1.2);
    s.pen_down = true;
    p.append(s);
  }
  io::writeProfileCsv(p, file, io::Overwrite::kReplace);
}

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
  EXPECT_THAT(message, HasSubstr("modes: mode: expected basic, pcontrol, alpha, mentor-observe, mentor-position, "
                                 "mentor-force or mentor-bilateral, got \"gamma\""));
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
  EXPECT_EQ(planTrials(s, "S01", s.modes).size(), 66u);
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
    EXPECT_THAT(e.what(), HasSubstr("study schema version 99 is newer than this build of hattr reads (1 to 3)"));
  }
}

TEST(StudyDatabase, MigratesTheFirstReleasedSchema) {
  StudyFolder folder;
  { (void)StudyDatabase::create(folder.dir / "s.sqlite", loadStudy(folder.dir / "study.json")); }
  // Turn it back into a version-1 file: what 1 -> 2 and 2 -> 3 added goes away.
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open((folder.dir / "s.sqlite").c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db,
                         "DROP TABLE disturbed_attempts; ALTER TABLE trials DROP COLUMN disturbed; DROP TABLE results; "
                         "ALTER TABLE trials DROP COLUMN interruptions; PRAGMA user_version = 1;",
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
    return t.plan.phase == Phase::kRecall && t.plan.mode != guidance::TrainingMode::kBasic;
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

TEST(SamplePacking, IsExact) {
  std::mt19937_64 rng(test::testSeed(17));
  for (const RawChannels raw : {RawChannels{}, RawChannels{true, true}}) {
    const HapticProfile p = test::randomProfile(rng, 300, raw);
    const auto back = decodeSamples(encodeSamples(p), raw, p.size());
    EXPECT_EQ(back, p.samples());
  }
  EXPECT_THROW((void)decodeSamples("short", RawChannels{}, 1), InputError);
}

}  // namespace
}  // namespace hattr::session
