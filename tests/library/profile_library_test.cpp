// The profile library's store, on SQLite and on a throwaway PostgreSQL server: profiles come back
// sample for sample, every change is all or none, and what is not a library (or is a newer one)
// is refused.

#include "hattr/library/profile_library.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sqlite3.h>

#include "hattr/core/error.hpp"
#include "hattr/library/sources.hpp"
#include "hattr/session/study_runner.hpp"
#include "library/synthetic_writers.hpp"
#include "session/study_fixture.hpp"
#include "support/postgres_cluster.hpp"
#include "support/test_support.hpp"

namespace hattr::library {
namespace {

using ::testing::HasSubstr;

EntryLabels labels(const std::string& key, const std::string& person, Authenticity a = Authenticity::kGenuine) {
  return {.key = key, .person = person, .skill = "signature", .session = "1", .date = "2026-11-30",
          .device = "synthetic", .source = "test", .authenticity = a};
}

/// The store's behaviour, the same on both engines.
void checkStore(const std::string& location) {
  ProfileLibrary lib = ProfileLibrary::create(location);
  const HapticProfile a = test::syntheticSignature(1, 0);
  const HapticProfile b = test::syntheticSignature(2, 0);
  const std::pair<EntryLabels, HapticProfile> two[] = {{labels("w1/0", "W1"), a}, {labels("w2/0", "W2"), b}};
  const auto ids = lib.add(two);
  ASSERT_EQ(ids.size(), 2u);
  // Sample for sample, metadata and all.
  EXPECT_EQ(lib.profile("w1/0"), a);
  EXPECT_EQ(lib.profile(ids[1]), b);
  const LibraryEntry e = lib.entry("w1/0");
  EXPECT_EQ(e.labels, labels("w1/0", "W1"));
  EXPECT_EQ(e.samples, a.size());
  EXPECT_NEAR(e.duration_s, a.duration_s(), 1e-12);

  // A duplicate key, in the batch or already stored, adds nothing.
  const std::pair<EntryLabels, HapticProfile> dup[] = {{labels("w3/0", "W3"), a}, {labels("w1/0", "W1"), a}};
  EXPECT_THAT(test::inputErrorOf([&] { lib.add(dup); }), HasSubstr("entry w1/0 is already in the library"));
  const std::pair<EntryLabels, HapticProfile> twice[] = {{labels("w4/0", "W4"), a}, {labels("w4/0", "W4"), a}};
  EXPECT_THAT(test::inputErrorOf([&] { lib.add(twice); }), HasSubstr("the key is given twice"));
  EXPECT_EQ(lib.list().size(), 2u);
  // Bad labels and an empty profile are refused before anything is written.
  EntryLabels bad = labels("w5/0", "W5");
  bad.date = "30.11.2026";
  EXPECT_THAT(test::inputErrorOf([&] { lib.add(bad, a); }), HasSubstr("date: expected YYYY-MM-DD"));
  bad = labels("w5/0", "");
  EXPECT_THAT(test::inputErrorOf([&] { lib.add(bad, a); }), HasSubstr("person: expected a name"));
  bad = labels("w5/0", "W5");
  bad.imitator = "someone";
  EXPECT_THAT(test::inputErrorOf([&] { lib.add(bad, a); }), HasSubstr("given for a genuine profile"));
  EXPECT_THAT(test::inputErrorOf([&] { lib.add(labels("w5/0", "W5"), HapticProfile()); }), HasSubstr("has no samples"));
  EXPECT_EQ(lib.list().size(), 2u);

  // Filters; persons; an imitation.
  lib.add(labels("w1/forged", "W1", Authenticity::kImitation), b);
  EXPECT_EQ(lib.list({.person = "W1"}).size(), 2u);
  EXPECT_EQ(lib.list({.authenticity = Authenticity::kImitation}).size(), 1u);
  EXPECT_EQ(lib.list({.skill = "na"}).size(), 0u);
  EXPECT_EQ(lib.persons("signature"), (std::vector<std::string>{"W1", "W2"}));

  // Remove is all or none.
  const std::vector<std::string> with_unknown{"w2/0", "nobody"};
  EXPECT_THAT(test::inputErrorOf([&] { lib.remove(with_unknown); }), HasSubstr("no entry nobody (nothing was removed)"));
  EXPECT_EQ(lib.list().size(), 3u);
  const std::vector<std::string> known{"w2/0"};
  lib.remove(known);
  EXPECT_EQ(lib.list().size(), 2u);
  EXPECT_THAT(test::inputErrorOf([&] { (void)lib.entry("w2/0"); }), HasSubstr("no entry w2/0"));

  // Settings persist.
  EXPECT_FALSE(lib.setting("x").has_value());
  lib.setSetting("x", "1");
  lib.setSetting("x", "2");
  EXPECT_EQ(ProfileLibrary::open(location, true).setting("x"), "2");
  // A second create refuses to touch it.
  EXPECT_THAT(test::inputErrorOf([&] { ProfileLibrary::create(location); }), HasSubstr("already"));
}

TEST(ProfileLibrary, SqliteStoresProfilesAndChangesAllOrNone) {
  test::TempDir dir;
  checkStore((dir / "lib.sqlite").string());
  // Nothing left beside it from building it.
  std::size_t files = 0;
  for (const auto& f : std::filesystem::directory_iterator(dir.path())) {
    EXPECT_EQ(f.path().filename().string().find(".building"), std::string::npos) << f.path();
    ++files;
  }
  EXPECT_GE(files, 1u);
}

TEST(ProfileLibrary, PostgresStoresProfilesAndChangesAllOrNone) {
  checkStore(test::PostgresCluster::shared().createDatabase("library"));
}

TEST(ProfileLibrary, RefusesWhatIsNotALibraryAndANewerSchema) {
  test::TempDir dir;
  EXPECT_THAT(test::inputErrorOf([&] { ProfileLibrary::open((dir / "none.sqlite").string()); }), HasSubstr("no such profile library"));
  // Another SQLite file.
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open((dir / "other.sqlite").c_str(), &db), SQLITE_OK);
  sqlite3_exec(db, "CREATE TABLE t (x); ", nullptr, nullptr, nullptr);
  sqlite3_close(db);
  EXPECT_THAT(test::inputErrorOf([&] { ProfileLibrary::open((dir / "other.sqlite").string()); }), HasSubstr("not a hattr profile library"));
  // A library of a newer schema.
  const std::string newer = (dir / "newer.sqlite").string();
  ProfileLibrary::create(newer);
  ASSERT_EQ(sqlite3_open(newer.c_str(), &db), SQLITE_OK);
  sqlite3_exec(db, "UPDATE library_meta SET value = '99' WHERE name = 'schema_version'", nullptr, nullptr, nullptr);
  sqlite3_close(db);
  EXPECT_THAT(test::inputErrorOf([&] { ProfileLibrary::open(newer); }), HasSubstr("schema 99, newer than this hattr reads"));
}

TEST(LibrarySources, AFolderThatIsNotSvc2004IsRefusedNamingWhatItExpected) {
  test::TempDir dir;
  test::writeText(dir / "notes.txt", "hello");
  EXPECT_THAT(test::inputErrorOf([&] { (void)readSvc2004Folder(dir.path(), io::svc2004Calibration()); }),
              HasSubstr("no U<writer>S<signature>.TXT file"));
  EXPECT_THAT(test::inputErrorOf([&] { (void)readSvc2004Folder(dir / "missing", io::svc2004Calibration()); }),
              HasSubstr("not a folder"));
  // Names that are not U<digits>S<digits>.TXT are not SVC2004 files and are passed over.
  for (const char* other : {"U1S1.txt", "UXS1.TXT", "U1S.TXT", "US1.TXT", "U1S1x.TXT", "u1s1.TXT", "U1T1.TXT"})
    test::writeText(dir / other, "1\n0 0 0 1 0 900 5\n");
  EXPECT_THAT(test::inputErrorOf([&] { (void)readSvc2004Folder(dir.path(), io::svc2004Calibration()); }),
              HasSubstr("no U<writer>S<signature>.TXT file"));
  test::writeText(dir / "U1S41.TXT", "1\n0 0 0 1 0 900 5\n");
  EXPECT_THAT(test::inputErrorOf([&] { (void)readSvc2004Folder(dir.path(), io::svc2004Calibration()); }),
              HasSubstr("signature 41 of writer 1; expected"));
  std::filesystem::remove(dir / "U1S41.TXT");
  test::writeText(dir / "U12345678901S1.TXT", "1\n0 0 0 1 0 900 5\n");
  EXPECT_THAT(test::inputErrorOf([&] { (void)readSvc2004Folder(dir.path(), io::svc2004Calibration()); }),
              HasSubstr("numbers 12345678901 and 1 in the name; expected at most 6 digits each"));
}

TEST(LibrarySources, Svc2004IsLabelledByWriterSessionAndForgery) {
  const auto folder = test::svc2004Folder();
  if (!folder) GTEST_SKIP() << "SVC2004 data not found at ../shared/data/svc2004-task2 beside the project";
  const auto entries = readSvc2004Folder(*folder, io::svc2004Calibration());
  ASSERT_EQ(entries.size(), 1600u);
  std::map<std::string, int> kinds;
  for (const auto& [l, p] : entries) {
    const int s = std::stoi(l.key.substr(l.key.find('S', 8) + 1));
    EXPECT_EQ(l.session, s <= 10 ? "1" : (s <= 20 ? "2" : "")) << l.key;
    EXPECT_EQ(l.authenticity, s <= 20 ? Authenticity::kGenuine : Authenticity::kImitation) << l.key;
    EXPECT_EQ(l.key, "svc2004/" + l.person + "S" + std::to_string(s));
    ++kinds[std::string(authenticityName(l.authenticity)) + l.session];
  }
  EXPECT_EQ(kinds["genuine1"], 400);
  EXPECT_EQ(kinds["genuine2"], 400);
  EXPECT_EQ(kinds["imitation"], 800);
}

TEST(LibrarySources, AStudysTrialsComeWithTheirSubjectSessionAndMode) {
  test::TempDir dir;
  session::writeExpert(dir / "expert.csv");
  test::writeText(dir / "study.json", R"({"name": "lib", "skill": "dash", "experts": {"dash": "expert.csv"},
    "modes": ["basic", "alpha"], "protocol": {"training_trials": 1, "recall_trials": 1, "rest_s": 0, "tail_s": 0.05},
    "world": {"relief": {"kind": "flat"}}, "subjects": {"count": 2, "participant": "script"}})");
  auto db = session::StudyDatabase::create(dir / "s.sqlite", session::loadStudy(dir / "study.json"));
  db = session::StudyDatabase::open(dir / "s.sqlite", session::OpenMode::kRunner);
  session::StudyRunner runner(db, &session::makeScriptParticipant);
  ASSERT_EQ(runner.run({}), 8);
  const auto entries = readStudyTrials(db);
  ASSERT_EQ(entries.size(), 8u);
  std::set<std::string> persons, modes;
  for (const auto& [l, p] : entries) {
    persons.insert(l.person);
    modes.insert(l.mode);
    EXPECT_EQ(l.skill, "dash");
    EXPECT_EQ(l.session, "1");
    EXPECT_THAT(l.key, HasSubstr("study/lib/trial-"));
  }
  EXPECT_EQ(persons.size(), 2u);
  EXPECT_EQ(modes, (std::set<std::string>{"BASIC", "ALPHA"}));
  // Added all at once, and each profile as the study stored it.
  ProfileLibrary lib = ProfileLibrary::create((dir / "lib.sqlite").string());
  lib.add(entries);
  EXPECT_EQ(lib.profile(entries[3].first.key), db.trialProfile(db.trials()[3].id));
}

}  // namespace
}  // namespace hattr::library
