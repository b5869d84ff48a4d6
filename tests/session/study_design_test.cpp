// Study designs (docs/studies.md "Designs"): groups, sessions on days, blocks; the shipped
// designs; the checks of an impossible design; the schedule's due dates; the runner following
// the schedule in simulated days and on the calendar; the migration to schema 5.

#include <sqlite3.h>

#include <map>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/session/study_export.hpp"
#include "hattr/session/study_runner.hpp"
#include "hattr/session/study_schedule.hpp"
#include "session/study_fixture.hpp"
#include "support/test_support.hpp"
#include "support/thread_sanitizer.hpp"

namespace hattr::session {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

/// A folder with the expert of "dash" (and of "dot", the same profile) for a study file.
struct DesignFolder {
  explicit DesignFolder(const std::string& definition) {
    writeExpert(dir / "expert.csv");
    writeExpert(dir / "dot.csv");
    test::writeText(dir / "study.json", definition);
  }
  test::TempDir dir;
};

/// Two groups of two script subjects, three sessions: baseline and training on day 0, training
/// and a post-test on day 1, retention and transfer to "dot" on day 3.
std::string twoGroups() {
  return R"({"name": "groups", "skill": "dash", "experts": {"dash": "expert.csv", "dot": "dot.csv"},
    "protocol": {"rest_s": 0, "tail_s": 0.05}, "order": {"kind": "fixed"},
    "world": {"relief": {"kind": "flat"}},
    "groups": [
      {"name": "path", "strategies": ["pcontrol"], "subjects": {"count": 2, "prefix": "P", "participant": "script"}},
      {"name": "force", "strategies": ["alpha"], "subjects": {"count": 2, "prefix": "A", "participant": "script"}}],
    "sessions": [
      {"day": 0, "blocks": [{"phase": "baseline", "trials": 1, "show_reference": true},
                            {"phase": "training", "strategy": "group", "trials": 2}]},
      {"day": 1, "blocks": [{"phase": "training", "strategy": "group", "trials": 2, "rest_s": 3},
                            {"phase": "post-test", "trials": 1}]},
      {"day": 3, "blocks": [{"phase": "retention", "trials": 1},
                            {"phase": "transfer", "skill": "dot", "trials": 1, "show_reference": true}]}]})";
}

std::string designError(const std::string& json, const std::filesystem::path& base) {
  try {
    (void)parseStudy(json, "design.json", base);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

// Every shipped design reads, and plans what it says; `paper` is the paper's form, unchanged.
TEST(StudyDesigns, EveryShippedDesignReadsAndPlansWhatItSays) {
  test::TempDir dir;
  writeExpert(dir / "expert.csv");
  writeExpert(dir / "loop.csv");
  std::map<std::string, std::size_t> trials_of_first_subject;
  std::map<std::string, std::size_t> subjects;
  for (const ExampleDesign& design : exampleDesigns()) {
    const StudyDefinition study = parseStudy(design.json, design.name, dir.path());
    const auto orders = modeOrders(study);
    trials_of_first_subject[std::string(design.name)] = planTrials(study, study.subjects.front(), orders.front()).size();
    subjects[std::string(design.name)] = study.subjects.size();
  }
  EXPECT_EQ(exampleDesigns().front().name, "paper");
  EXPECT_EQ(exampleStudyJson(), exampleDesign("paper").json);
  EXPECT_TRUE(isPaperDesign(parseStudy(exampleStudyJson(), "paper", dir.path())));
  EXPECT_EQ(trials_of_first_subject["paper"], 66u);             // 3 modes × (11 + 11)
  EXPECT_EQ(trials_of_first_subject["groups-retention"], 40u);  // 5 + 10, 10 + 5, 5 + 5
  EXPECT_EQ(trials_of_first_subject["week-apart"], 132u);       // the paper's, twice
  EXPECT_EQ(trials_of_first_subject["learner"], 14u + 5 * 11 + 3);
  EXPECT_EQ(trials_of_first_subject["fading"], 45u);            // 5 + 10, 10, 10 + 5, 5
  EXPECT_EQ(subjects["groups-retention"], 24u);
  EXPECT_EQ(subjects["learner"], 1u);
  EXPECT_THROW((void)exampleDesign("nonesuch"), InputError);
}

// The paper's protocol written as a design (one group, one session, a block per mode and
// phase) is the same study: the same plan, and the same trials to the bit.
TEST(StudyDesigns, ThePapersProtocolWrittenAsADesignIsTheSameStudy) {
  HATTR_STARTS_NO_THREAD();
  const std::string paper_form = R"({"name": "p", "skill": "dash", "experts": {"dash": "expert.csv"},
    "modes": ["basic", "pcontrol", "alpha"],
    "protocol": {"training_trials": 2, "recall_trials": 1, "rest_s": 0, "tail_s": 0.05},
    "world": {"relief": {"kind": "flat"}},
    "subjects": {"count": 3, "participant": "script", "options": {"jitter_mm": 1.0}}})";
  std::string blocks;
  for (int k = 1; k <= 3; ++k) {
    blocks += fmt::format(R"({}{{"phase": "training", "strategy": {{"order": {}}}, "trials": 2}},
        {{"phase": "recall", "strategy": {{"order": {}}}, "guidance": false, "trials": 1}})",
                          k == 1 ? "" : ",", k, k);
  }
  const std::string design = R"({"name": "p", "skill": "dash", "experts": {"dash": "expert.csv"},
    "protocol": {"rest_s": 0, "tail_s": 0.05}, "world": {"relief": {"kind": "flat"}},
    "groups": [{"name": "all", "strategies": ["basic", "pcontrol", "alpha"],
                "subjects": {"count": 3, "participant": "script", "options": {"jitter_mm": 1.0}}}],
    "sessions": [{"day": 0, "blocks": [)" + blocks + "]}]}";
  DesignFolder a(paper_form), b(design);
  const StudyDefinition sa = loadStudy(a.dir / "study.json"), sb = loadStudy(b.dir / "study.json");
  EXPECT_TRUE(isPaperDesign(sa));
  EXPECT_FALSE(isPaperDesign(sb));
  const auto oa = modeOrders(sa), ob = modeOrders(sb);
  ASSERT_EQ(oa, ob);
  for (std::size_t s = 0; s < sa.subjects.size(); ++s) {
    const auto pa = planTrials(sa, sa.subjects[s], oa[s]), pb = planTrials(sb, sb.subjects[s], ob[s]);
    ASSERT_EQ(pa.size(), pb.size());
    for (std::size_t i = 0; i < pa.size(); ++i) {
      EXPECT_EQ(pa[i].mode, pb[i].mode);
      EXPECT_EQ(pa[i].phase, pb[i].phase);
      EXPECT_EQ(pa[i].index, pb[i].index);
      EXPECT_EQ(pa[i].view.guidance, pb[i].view.guidance);
      EXPECT_EQ(pa[i].view.show_reference, pb[i].view.show_reference);
      EXPECT_EQ(pa[i].block, pb[i].block);
    }
  }
  // Both run to the same samples.
  StudyDatabase da = StudyDatabase::create(a.dir / "s.sqlite", sa), db = StudyDatabase::create(b.dir / "s.sqlite", sb);
  da = StudyDatabase::open(a.dir / "s.sqlite", OpenMode::kRunner);
  db = StudyDatabase::open(b.dir / "s.sqlite", OpenMode::kRunner);
  ASSERT_EQ(StudyRunner(da, makeScriptParticipant).run({}), 27);
  ASSERT_EQ(StudyRunner(db, makeScriptParticipant).run({}), 27);
  const auto ta = da.trials(), tb = db.trials();
  for (std::size_t i = 0; i < ta.size(); ++i) {
    EXPECT_EQ(da.trialProfile(ta[i].id).samples(), db.trialProfile(tb[i].id).samples()) << "trial " << i;
  }
}

// An impossible design is refused with every problem at once, one a line, each key named.
TEST(StudyDesigns, AnImpossibleDesignIsRefusedWithEveryProblemAtOnce) {
  test::TempDir dir;
  writeExpert(dir / "expert.csv");
  const std::string message = designError(R"({"name": "x", "skill": "dash", "experts": {"dash": "expert.csv"},
    "protocol": {"training_trials": 5},
    "groups": [{"name": "a", "strategies": ["alpha", "gamma"], "subjects": {"count": 2}},
               {"name": "b", "strategies": ["basic"]}],
    "sessions": [
      {"day": 2, "blocks": [{"phase": "retention", "trials": 3},
                            {"phase": "training", "skill": "nu", "strategy": "beta", "trials": 2}]},
      {"day": 1, "blocks": [{"phase": "training", "strategy": {"order": 2}, "trials": 0, "colour": "red"}]}]})",
                                         dir.path());
  EXPECT_THAT(message, HasSubstr("design.json: 10 problems in the study definition:"));
  EXPECT_THAT(message, HasSubstr("protocol.training_trials: only in the paper's form"));
  EXPECT_THAT(message, HasSubstr("groups[1].strategies: "));
  EXPECT_THAT(message, HasSubstr("groups[2].subjects: missing: a group without subjects"));
  EXPECT_THAT(message, HasSubstr("sessions[1].blocks[1].phase: a retention block before any training block"));
  EXPECT_THAT(message, HasSubstr("sessions[1].blocks[2].skill: \"nu\" has no expert reference in experts"));
  EXPECT_THAT(message, HasSubstr("sessions[1].blocks[2].strategy: expected \"none\", \"group\""));
  EXPECT_THAT(message, HasSubstr("sessions[2].day: 1 goes back before sessions[1]'s day 2"));
  EXPECT_THAT(message, HasSubstr("sessions[2].blocks[1].trials: expected an integer in [1, 1000], got 0"));
  EXPECT_THAT(message, HasSubstr("sessions[2].blocks[1].colour: unknown key"));
  EXPECT_THAT(message, HasSubstr("sessions[2].blocks[1].strategy: position 2 of the subject's order, but a group has "
                                 "only 1 strategy"));
}

// A group design plans each subject's blocks with its group's strategy, its skills and days.
TEST(StudyDesigns, AGroupDesignPlansEachSubjectsSessionsAndBlocks) {
  DesignFolder folder(twoGroups());
  const StudyDefinition study = loadStudy(folder.dir / "study.json");
  ASSERT_EQ(study.subjects.size(), 4u);
  EXPECT_EQ(study.subjects[2].id, "A01");
  EXPECT_EQ(study.subjects[2].group, "force");
  EXPECT_EQ(study.subjects[2].seed, 3u) << "seeds run on across the groups";
  EXPECT_THAT(study.modes, ElementsAre(guidance::TrainingMode::kPositionControl, guidance::TrainingMode::kForceControl));
  const auto plan = planTrials(study, study.subjects[2], modeOrders(study)[2]);
  ASSERT_EQ(plan.size(), 8u);
  std::vector<std::string> phases;
  for (const TrialPlan& p : plan) phases.push_back(fmt::format("{}{}:{}", p.day, p.phase, p.view.guidance ? "+" : ""));
  EXPECT_THAT(phases, ElementsAre("0baseline:", "0training:+", "0training:+", "1training:+", "1training:+",
                                  "1post-test:", "3retention:", "3transfer:"));
  EXPECT_EQ(plan[1].mode, guidance::TrainingMode::kForceControl);
  EXPECT_EQ(plan[7].skill, "dot");
  EXPECT_TRUE(plan[7].view.show_reference);
  EXPECT_FALSE(plan[6].view.show_reference);
  EXPECT_EQ(blockOf(study, plan[3]).rest_s, 3.0);
  // Written back and read again, the design is the same.
  const StudyDefinition again = parseStudy(studyToJson(study).dump(), "again", "", false);
  EXPECT_EQ(studyToJson(again), studyToJson(study));
}

/// A script participant that notes the days it is told about.
class DaysParticipant : public Participant {
 public:
  DaysParticipant(std::unique_ptr<Participant> inner, std::vector<std::string>& log, std::string skill)
      : inner_(std::move(inner)), log_(log), skill_(std::move(skill)) {}
  device::HandScript& handForTrial(const TrialPlan& plan) override { return inner_->handForTrial(plan); }
  void trialCompleted(const TrialPlan& plan, const HapticProfile& recorded) override {
    inner_->trialCompleted(plan, recorded);
  }
  void daysPassed(int days) override { log_.push_back(fmt::format("{}+{}", skill_, days)); }

 private:
  std::unique_ptr<Participant> inner_;
  std::vector<std::string>& log_;
  std::string skill_;
};

// In simulated days, each session follows at once and every participant the subject has is
// told how many days passed, the same on a resume as in one run.
TEST(StudyDesigns, SimulatedDaysPassBetweenSessionsAlikeInOneRunAndOnResume) {
  HATTR_STARTS_NO_THREAD();
  DesignFolder folder(twoGroups());
  const StudyDefinition study = loadStudy(folder.dir / "study.json");
  const auto logged_run = [&](const std::string& file, const std::vector<int>& stops) {
    std::vector<std::string> log;
    { (void)StudyDatabase::create(folder.dir / file, study); }
    StudyDatabase db = StudyDatabase::open(folder.dir / file, OpenMode::kRunner);
    for (const int stop : stops) {
      log.push_back("run");
      const ParticipantFactory factory = [&log](const SubjectRecord& s, const HapticProfile& expert) {
        return std::make_unique<DaysParticipant>(makeScriptParticipant(s, expert), log, expert.metadata().skill);
      };
      (void)StudyRunner(db, factory).run({.only_subject = "P01", .max_trials = stop});
    }
    return log;
  };
  const auto once = logged_run("once.sqlite", {-1});
  EXPECT_THAT(once, ElementsAre("run", "dash+1", "dash+2")) << "the transfer's participant is made on day 3";
  // Stopped within day 0, at the end of day 1, and within day 3: each resume relives its days.
  const auto resumed = logged_run("resumed.sqlite", {2, 4, 1, -1});
  EXPECT_THAT(resumed, ElementsAre("run", "run", "dash+1", "run", "dash+1", "dash+2", "run", "dash+1", "dash+2"));
}

TrialRecord startedTrial(int session, int day, const std::string& started_utc, TrialStatus status) {
  TrialRecord t;
  t.plan.session = session;
  t.plan.day = day;
  t.started_utc = started_utc;
  t.status = status;
  return t;
}

// The due date: the subject's first session's local date plus the day offsets; a session
// begun goes on; early, due and overdue counted in days.
TEST(StudySchedule, ASessionIsDueOnItsDayAfterTheFirstAndABegunSessionGoesOn) {
  ::setenv("TZ", "UTC", 1);
  ::tzset();
  DesignFolder folder(twoGroups());
  const StudyDefinition study = loadStudy(folder.dir / "study.json");
  const auto done = TrialStatus::kCompleted, pending = TrialStatus::kPending;
  std::vector<TrialRecord> trials{startedTrial(0, 0, "2026-11-30T23:10:00Z", done),
                                  startedTrial(0, 0, "2026-11-30T23:20:00Z", done), startedTrial(1, 1, "", pending),
                                  startedTrial(2, 3, "", pending)};
  const LocalDate nov30{2026, 11, 30};
  SubjectSchedule s = subjectSchedule(study, trials, nov30);
  EXPECT_EQ(s.timing, SubjectSchedule::Timing::kEarly);
  EXPECT_EQ(s.session, 1);
  EXPECT_EQ(s.due->iso(), "2026-12-01");
  EXPECT_EQ(s.days_off, 1);
  EXPECT_FALSE(s.runnable());
  EXPECT_EQ(scheduleText(s), "next: session 2 of 3 (day 1), due on 2026-12-01 (in 1 day): early");
  EXPECT_EQ(subjectSchedule(study, trials, addDays(nov30, 1)).timing, SubjectSchedule::Timing::kDue);
  s = subjectSchedule(study, trials, LocalDate{2027, 1, 2});
  EXPECT_EQ(s.timing, SubjectSchedule::Timing::kOverdue);
  EXPECT_EQ(s.days_off, 32);
  EXPECT_TRUE(s.runnable());
  trials[2].started_utc = "2026-12-03T08:00:00Z";  // begun (late): it goes on
  EXPECT_EQ(subjectSchedule(study, trials, nov30).timing, SubjectSchedule::Timing::kInProgress);
  trials[2].status = done;
  s = subjectSchedule(study, trials, LocalDate{2026, 12, 2});
  EXPECT_EQ(s.due->iso(), "2026-12-03") << "day 3 counts from the first session, not the late one";
  EXPECT_EQ(s.timing, SubjectSchedule::Timing::kEarly);
  // Local dates: a first session at 23:10 UTC is on Dec 1 in Sydney.
  ::setenv("TZ", "Australia/Sydney", 1);
  ::tzset();
  EXPECT_EQ(localDateOfUtc("2026-11-30T23:10:00Z").iso(), "2026-12-01");
  ::setenv("TZ", "UTC", 1);
  ::tzset();
  EXPECT_EQ(subjectSchedule(study, {startedTrial(0, 0, "", pending)}, nov30).timing, SubjectSchedule::Timing::kAnyTime);
  EXPECT_EQ(addDays(LocalDate{2028, 2, 28}, 1).iso(), "2028-02-29");
  EXPECT_EQ(daysBetween(LocalDate{2026, 12, 31}, LocalDate{2027, 3, 1}), 60);
  EXPECT_THROW((void)localDateOfUtc("yesterday"), InputError);
}

// Following the calendar, a run stops at a session's end until the next is due, and says so.
TEST(StudyDesigns, OnTheCalendarARunWaitsForTheNextSessionsDate) {
  HATTR_STARTS_NO_THREAD();
  DesignFolder folder(twoGroups());
  { (void)StudyDatabase::create(folder.dir / "s.sqlite", loadStudy(folder.dir / "study.json")); }
  StudyDatabase db = StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kRunner);
  const LocalDate today = localToday();
  StudyRunner runner(db, makeScriptParticipant);
  EXPECT_EQ(runner.run({.only_subject = "P01", .follow_calendar = true, .today = today}), 3) << "day 0's session";
  ASSERT_EQ(runner.waiting().size(), 1u);
  EXPECT_EQ(runner.waiting()[0].subject, "P01");
  EXPECT_EQ(runner.waiting()[0].schedule.timing, SubjectSchedule::Timing::kEarly);
  EXPECT_EQ(runner.waiting()[0].schedule.due, addDays(today, 1));
  EXPECT_EQ(runner.run({.only_subject = "P01", .follow_calendar = true, .today = today}), 0);
  EXPECT_EQ(runner.run({.only_subject = "P01", .follow_calendar = true, .today = addDays(today, 1)}), 3);
  EXPECT_EQ(runner.run({.only_subject = "P01", .follow_calendar = true, .today = addDays(today, 5)}), 2)
      << "overdue: it runs";
  EXPECT_TRUE(runner.waiting().empty());
}

// A study written before designs (schema 4) opens and is brought to schema 5: every trial's
// place in the design filled in from its definition, and the subjects in the paper's group.
TEST(StudyDesigns, ASchema4StudyGetsItsTrialsPlacesInTheDesign) {
  DesignFolder folder(R"({"name": "old", "skill": "dash", "experts": {"dash": "expert.csv"},
    "modes": ["basic", "alpha"], "protocol": {"training_trials": 2, "recall_trials": 1, "rest_s": 0, "tail_s": 0.05},
    "subjects": {"count": 2, "participant": "script"}})");
  std::vector<TrialRecord> before;
  {
    StudyDatabase db = StudyDatabase::create(folder.dir / "s.sqlite", loadStudy(folder.dir / "study.json"));
    before = db.trials();
  }
  sqlite3* raw = nullptr;
  ASSERT_EQ(sqlite3_open((folder.dir / "s.sqlite").c_str(), &raw), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(raw, (std::string(kBackToSchema4) + "PRAGMA user_version = 4;").c_str(), nullptr, nullptr,
                         nullptr),
            SQLITE_OK);
  sqlite3_close(raw);
  const StudyDatabase migrated = StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kReadWrite);
  EXPECT_EQ(migrated.schemaVersion(), 5);
  const auto after = migrated.trials();
  ASSERT_EQ(after.size(), before.size());
  for (std::size_t i = 0; i < after.size(); ++i) {
    EXPECT_EQ(after[i].plan.skill, "dash");
    EXPECT_EQ(after[i].plan.group, "all");
    EXPECT_EQ(after[i].plan.session, 0);
    EXPECT_EQ(after[i].plan.block, before[i].plan.block) << "trial " << i;
  }
  EXPECT_EQ(after[3].plan.block, 2) << "the second mode's training block";
  EXPECT_EQ(migrated.subjects()[1].spec.group, "all");
}

// A design's export has each trial's place; its import is the same study. An export written
// before designs (15 columns) still imports.
TEST(StudyDesigns, ADesignExportsWithEachTrialsPlaceAndImportsAgain) {
  HATTR_STARTS_NO_THREAD();
  DesignFolder folder(twoGroups());
  { (void)StudyDatabase::create(folder.dir / "s.sqlite", loadStudy(folder.dir / "study.json")); }
  StudyDatabase db = StudyDatabase::open(folder.dir / "s.sqlite", OpenMode::kRunner);
  ASSERT_EQ(StudyRunner(db, makeScriptParticipant).run({.only_subject = "A02"}), 8);
  ASSERT_EQ(exportStudy(db, folder.dir / "export"), 8u);
  const std::string table = test::readText(folder.dir / "export" / "trials.csv");
  EXPECT_THAT(table, HasSubstr(",samples,file,skill,group,session,day,block\n"));
  EXPECT_THAT(table, HasSubstr("_transfer_01.csv,dot,force,3,3,2\n"));
  ASSERT_EQ(importStudy(folder.dir / "export", folder.dir / "copy.sqlite"), 8u);
  const StudyDatabase copy = StudyDatabase::open(folder.dir / "copy.sqlite", OpenMode::kReadOnly);
  EXPECT_FALSE(isPaperDesign(copy.study()));
  EXPECT_EQ(studyToJson(copy.study())["sessions"], studyToJson(db.study())["sessions"]);
  // The same export cut to the first 15 columns, as hattr wrote it before designs.
  std::string old_table;
  std::istringstream lines(table);
  for (std::string line; std::getline(lines, line);) {
    std::size_t cut = 0;
    for (int commas = 0; commas < 15 && cut != std::string::npos; ++commas) cut = line.find(',', cut + 1);
    old_table += line.substr(0, cut) + "\n";
  }
  test::writeText(folder.dir / "export" / "trials.csv", old_table);
  EXPECT_EQ(importStudy(folder.dir / "export", folder.dir / "old.sqlite"), 8u);
}

}  // namespace
}  // namespace hattr::session
