// A learner's practice plan and progress (issue 39): the plan made from the `learner` design, the
// practice folder listed, a simulated learner's plan run and its progress computed and printed.

#include "hattr/ops/practice_plan.hpp"

#include <cmath>
#include <map>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/ops/study_run.hpp"
#include "hattr/report/learner_progress.hpp"
#include "hattr/session/study_database.hpp"
#include "hattr/sim/expert.hpp"
#include "support/test_support.hpp"
#include "support/thread_sanitizer.hpp"

namespace hattr::ops {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

PracticePlanOptions planFor(const std::string& code, std::vector<std::string> letters) {
  return {.learner = {.code = code, .name = "Mia Example", .age_years = 7, .handedness = "left", .notes = "grips hard"},
          .letters = std::move(letters),
          .strategy = guidance::TrainingMode::kPositionControl,
          .sessions = 3,
          .trials_per_session = 2,
          .check_trials = 2,
          .days_between = 2,
          .retention_after_days = 7,
          .rest_s = 0.0};
}

TEST(PracticePlan, IsTheLearnerDesignForTheLearnerLettersAndStrategy) {
  HATTR_STARTS_NO_THREAD();
  const session::StudyDefinition study = practicePlanStudy(planFor("mia", {"a", "B"}));
  EXPECT_EQ(study.name, "Practice of a, B for mia");
  ASSERT_EQ(study.subjects.size(), 1u);
  EXPECT_EQ(study.subjects[0].id, "mia");
  EXPECT_EQ(study.subjects[0].participant, "person");
  EXPECT_EQ(session::learnerOf(study.subjects[0]).notes, "grips hard");
  EXPECT_EQ(study.groups.at(0).strategies, std::vector{guidance::TrainingMode::kPositionControl});
  EXPECT_EQ(study.named_experts.at("small-a"), "small-a");
  EXPECT_EQ(study.named_experts.at("capital-b"), "capital-b");
  // Three sessions two days apart, then the retention check seven days after the last.
  ASSERT_EQ(study.schedule.size(), 4u);
  EXPECT_EQ(study.schedule[1].day, 2);
  EXPECT_EQ(study.schedule[2].day, 4);
  EXPECT_EQ(study.schedule[3].day, 11);
  // Session 1: each letter before practice (model shown, no help), then each letter's guided
  // trials and its trials written alone (model hidden).
  std::vector<std::string> blocks;
  for (const auto& b : study.schedule[0].blocks) {
    blocks.push_back(b.phase + " " + b.skill + " " + std::to_string(b.trials) + (b.view.guidance ? " guided" : "") +
                     (b.view.show_reference ? " shown" : ""));
  }
  EXPECT_EQ(blocks, (std::vector<std::string>{"baseline small-a 2 shown", "baseline capital-b 2 shown",
                                              "training small-a 2 guided shown", "post-test small-a 2",
                                              "training capital-b 2 guided shown", "post-test capital-b 2"}));
  EXPECT_EQ(study.schedule[1].blocks.size(), 4u);
  ASSERT_EQ(study.schedule[3].blocks.size(), 2u);
  EXPECT_EQ(study.schedule[3].blocks[0].phase, "retention");
}

TEST(PracticePlan, EveryProblemOfTheOptionsIsListedAtOnce) {
  HATTR_STARTS_NO_THREAD();
  PracticePlanOptions bad = planFor("m i", {"a", "zz", "a"});
  bad.sessions = 0;
  bad.check_trials = 0;
  bad.strategy = guidance::TrainingMode::kMentorForce;
  try {
    (void)practicePlanStudy(bad);
    FAIL() << "a bad plan was accepted";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_THAT(m, HasSubstr("practice plan: 6 problems:"));
    EXPECT_THAT(m, HasSubstr("learner code \"m i\""));
    EXPECT_THAT(m, HasSubstr("sessions: expected 1 to 60, got 0"));
    EXPECT_THAT(m, HasSubstr("retention after 7 days: it is made of check trials; expected check trials above 0"));
    EXPECT_THAT(m, HasSubstr("strategy MENTOR-FORCE: a mentored strategy needs a live expert"));
    EXPECT_THAT(m, HasSubstr("letters: \"zz\": not a letter of the library"));
    EXPECT_THAT(m, HasSubstr("letters: \"a\" given twice"));
  }
}

TEST(PracticePlan, PlansAreNumberedPerLearnerAndListedInOrder) {
  HATTR_STARTS_NO_THREAD();
  test::TempDir dir;
  PracticePlanOptions plan = planFor("mia", {"a"});
  plan.sessions = 1;
  plan.retention_after_days = 0;
  EXPECT_EQ(createPracticePlan(dir.path(), plan), dir / "mia" / "plan-1.sqlite");
  EXPECT_EQ(createPracticePlan(dir.path(), plan), dir / "mia" / "plan-2.sqlite");
  EXPECT_EQ(createPracticePlan(dir.path(), planFor("ada", {"7"})), dir / "ada" / "plan-1.sqlite");
  test::writeText(dir / "mia" / "plan-9.sqlite", "not a study");
  // Not plan files: left alone, neither listed nor skipped.
  for (const char* other : {"plan-old.sqlite", "plan-.sqlite", "plan-1 copy.sqlite", "plan-99999999999.sqlite"}) {
    test::writeText(dir / "mia" / other, "whatever");
  }
  std::vector<std::string> skipped;
  const auto plans = listPracticePlans(dir.path(), session::localToday(), &skipped);
  ASSERT_EQ(plans.size(), 3u);
  EXPECT_EQ(plans[0].file, dir / "ada" / "plan-1.sqlite");
  EXPECT_EQ(plans[0].letters, std::vector<std::string>{"7"});
  EXPECT_EQ(plans[1].file, dir / "mia" / "plan-1.sqlite");
  EXPECT_EQ(plans[2].file, dir / "mia" / "plan-2.sqlite");
  EXPECT_EQ(plans[2].learner.name, "Mia Example");
  EXPECT_EQ(plans[2].trials_total, 2 + 2 + 2);
  EXPECT_EQ(plans[2].trials_completed, 0);
  EXPECT_EQ(plans[2].schedule.timing, session::SubjectSchedule::Timing::kAnyTime);
  ASSERT_EQ(skipped.size(), 1u);
  EXPECT_THAT(skipped[0], HasSubstr("plan-9.sqlite"));
  EXPECT_EQ(toJson(plans[2])["plain_strategy"], "Guided path");
  // A folder that is not there is refused, naming it.
  EXPECT_THAT([&] { (void)listPracticePlans(dir / "missing", session::localToday()); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("missing: expected a folder, got nothing there")));
}

// A simulated learner writes the whole plan; the progress is derived again here from its trials.
class LearnerProgressTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir;
    session::StudyDefinition study = practicePlanStudy(planFor("mia", {"a"}));
    study.subjects[0].participant = "simulated";  // the learner's details stay
    sim::recordNamedExperts(study);
    file_ = *dir_ / "plan.sqlite";
    (void)session::StudyDatabase::create(file_, study);
    (void)runStudy({.db = file_});
  }
  static void TearDownTestSuite() { delete dir_; }
  static test::TempDir* dir_;
  static std::filesystem::path file_;
};
test::TempDir* LearnerProgressTest::dir_ = nullptr;
std::filesystem::path LearnerProgressTest::file_;

double meanOf(const std::vector<double>& v) {
  double s = 0.0;
  for (const double x : v) s += x / static_cast<double>(v.size());
  return s;
}

TEST_F(LearnerProgressTest, EachSessionIsMeasuredAgainstTheStart) {
  const auto db = session::StudyDatabase::open(file_, session::OpenMode::kReadOnly);
  const report::LearnerProgress p = report::learnerProgress(db);
  EXPECT_EQ(p.learner.name, "Mia Example");
  EXPECT_EQ(p.letters, std::vector<std::string>{"a"});
  EXPECT_EQ(p.strategy, "Guided path");
  EXPECT_EQ(p.next, "done");
  ASSERT_EQ(p.trials.size(), 6u + 4u + 4u + 2u);
  ASSERT_EQ(p.sessions.size(), 4u);
  // The start: the baseline's mean shape; each session: its trials written alone after it.
  std::vector<double> baseline;
  std::map<int, std::vector<double>> alone;
  for (const auto& t : p.trials) {
    EXPECT_EQ(t.guided, t.phase == "training") << t.number;
    if (t.phase == "baseline") baseline.push_back(t.shape);
    if (!t.guided && t.phase != "baseline") alone[t.session].push_back(t.shape);
  }
  const double start = meanOf(baseline);
  for (const auto& s : p.sessions) {
    SCOPED_TRACE(s.sentence);
    EXPECT_EQ(s.completed, s.planned);
    EXPECT_NEAR(s.alone_shape, meanOf(alone.at(s.session)), 1e-9);
    const double change = (start - s.alone_shape) / start;
    EXPECT_NEAR(s.change, change, 1e-9);
    EXPECT_THAT(s.sentence, HasSubstr("Session " + std::to_string(s.session) + " (" + p.trials.front().date + ")"));
    EXPECT_FALSE(s.is_start) << "session 1 has a baseline and trials after it";
    if (std::abs(change) < 0.05) {
      EXPECT_THAT(s.sentence, HasSubstr("the shape was about the same as at the start"));
    } else {
      EXPECT_THAT(s.sentence, HasSubstr(fmt::format("the shape was {:.0f} % {} the model than at the start",
                                                    std::abs(change) * 100.0, change > 0 ? "closer to" : "further from")));
    }
  }
  EXPECT_THAT(p.sessions[0].sentence, HasSubstr("2 guided trials and 4 written alone (a)"));
  EXPECT_THAT(p.sessions[3].sentence, HasSubstr("2 trials written alone (a)"));
}

TEST_F(LearnerProgressTest, TheBestAndTheLatestAreAmongTheLettersWrittenAlone) {
  const auto db = session::StudyDatabase::open(file_, session::OpenMode::kReadOnly);
  const report::LearnerProgress p = report::learnerProgress(db, "mia");
  const report::ProgressTrial* best = nullptr;
  const report::ProgressTrial* last_alone = nullptr;
  for (const auto& t : p.trials) {
    if (t.guided) continue;
    if (best == nullptr || t.shape < best->shape) best = &t;
    last_alone = &t;
  }
  for (const auto& t : p.trials) {
    EXPECT_EQ(t.best, &t == best) << t.number;
    EXPECT_EQ(t.latest, &t == last_alone) << t.number;
  }
  // A session is the best so far when its change from the start is at least 5 % and above every
  // earlier session's; the sentence says so only then.
  double best_change = 0.0;
  for (const auto& s : p.sessions) {
    const bool best_so_far = s.change >= 0.05 && s.change > best_change;
    EXPECT_EQ(s.best_so_far, best_so_far) << s.session;
    EXPECT_EQ(s.sentence.find("the best so far") != std::string::npos, best_so_far) << s.sentence;
    if (best_so_far) best_change = s.change;
  }
  EXPECT_THAT([&] { (void)report::learnerProgress(db, "ana"); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("no subject \"ana\"")));
}

TEST_F(LearnerProgressTest, ThePrintablePageNamesTheLearnerOnlyWhenAsked) {
  const auto db = session::StudyDatabase::open(file_, session::OpenMode::kReadOnly);
  const report::LearnerProgress p = report::learnerProgress(db);
  const std::string page = report::progressPageHtml(p, {.identified = true, .printed = "2026-11-29"});
  for (const char* expected : {"<title>Progress of Mia Example</title>", "Progress of Mia Example (mia)",
                               "age 7 · left-handed", "Notes: grips hard", "printed 2026-11-29", "<svg", "★ best",
                               "● latest", "before practice", "alone, days later"}) {
    EXPECT_THAT(page, HasSubstr(expected));
  }
  for (const auto& s : p.sessions) EXPECT_THAT(page, HasSubstr(s.sentence));
  const std::string plain = report::progressPageHtml(p, {.identified = false});
  EXPECT_THAT(plain, HasSubstr("Progress of learner mia"));
  EXPECT_THAT(plain, Not(HasSubstr("Mia Example")));
  EXPECT_THAT(plain, Not(HasSubstr("grips hard")));
  const std::string view = report::progressPageHtml(p, {.whole_page = false});
  EXPECT_THAT(view, Not(HasSubstr("<svg")));
  EXPECT_THAT(view, Not(HasSubstr("<h1>")));
  EXPECT_THAT(view, HasSubstr("★ best"));
}

// Two letters, every trial guided (no trials written alone): the guided trials are compared,
// session 1 is the start, session 2's change is the letters' changes averaged.
TEST(LearnerProgress, APlanWithoutTrialsWrittenAloneComparesItsGuidedTrialsLetterByLetter) {
  test::TempDir dir;
  PracticePlanOptions plan = planFor("ada", {"a", "b"});
  plan.sessions = 2;
  plan.check_trials = 0;
  plan.retention_after_days = 0;
  session::StudyDefinition study = practicePlanStudy(plan);
  study.subjects[0].participant = "simulated";
  sim::recordNamedExperts(study);
  (void)session::StudyDatabase::create(dir / "plan.sqlite", study);
  (void)runStudy({.db = dir / "plan.sqlite"});
  const auto db = session::StudyDatabase::open(dir / "plan.sqlite", session::OpenMode::kReadOnly);
  const report::LearnerProgress p = report::learnerProgress(db);
  EXPECT_FALSE(p.compares_alone);
  ASSERT_EQ(p.trials.size(), 8u);
  ASSERT_EQ(p.sessions.size(), 2u);
  EXPECT_TRUE(p.sessions[0].is_start);
  EXPECT_THAT(p.sessions[0].sentence, HasSubstr("4 guided trials (a, b); with guidance, this is the starting point"));
  std::map<std::string, std::vector<double>> first, second;
  for (const auto& t : p.trials) (t.session == 1 ? first : second)[t.skill].push_back(t.shape);
  const double change_a = (meanOf(first["a"]) - meanOf(second["a"])) / meanOf(first["a"]);
  const double change_b = (meanOf(first["b"]) - meanOf(second["b"])) / meanOf(first["b"]);
  EXPECT_FALSE(p.sessions[1].is_start);
  EXPECT_NEAR(p.sessions[1].change, (change_a + change_b) / 2.0, 1e-9);
  EXPECT_NEAR(p.sessions[1].alone_shape, (meanOf(second["a"]) + meanOf(second["b"])) / 2.0, 1e-9);
  int best = 0;
  for (const auto& t : p.trials) best += t.best ? 1 : 0;
  EXPECT_EQ(best, 2) << "one best a letter, among the guided trials";
  const std::string page = report::progressPageHtml(p);
  EXPECT_THAT(page, HasSubstr("best (guided)"));
  EXPECT_THAT(page, HasSubstr("every trial of this plan is guided"));
  EXPECT_THAT(page, Not(HasSubstr("best (written alone)")));
}

TEST(LearnerProgress, APlanNotBegunSaysSo) {
  HATTR_STARTS_NO_THREAD();
  test::TempDir dir;
  const auto file = createPracticePlan(dir.path(), planFor("mia", {"a"}));
  const auto db = session::StudyDatabase::open(file, session::OpenMode::kReadOnly);
  const report::LearnerProgress p = report::learnerProgress(db);
  EXPECT_TRUE(p.trials.empty());
  ASSERT_EQ(p.sessions.size(), 4u);
  EXPECT_EQ(p.sessions[0].sentence, "Session 1: not begun yet.");
  EXPECT_EQ(p.next, "next: session 1 of 4 (day 0), any time");
  EXPECT_THAT(report::progressPageHtml(p), HasSubstr("No trial written yet."));
}

}  // namespace
}  // namespace hattr::ops
