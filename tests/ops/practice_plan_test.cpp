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
    EXPECT_THAT(m, HasSubstr("retention: it is made of check trials"));
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
    EXPECT_THAT(s.sentence, HasSubstr("Session " + std::to_string(s.session) + " (" + session::localToday().iso() + ")"));
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
  // A session is the best so far when its shape is below every earlier session's.
  double lowest = std::numeric_limits<double>::infinity();
  for (const auto& s : p.sessions) {
    EXPECT_EQ(s.best_so_far, s.alone_shape < lowest) << s.session;
    lowest = std::min(lowest, s.alone_shape);
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
  for (const auto& s : p.sessions) EXPECT_THAT(page, HasSubstr(s.sentence.substr(0, 20)));
  const std::string plain = report::progressPageHtml(p, {.identified = false});
  EXPECT_THAT(plain, HasSubstr("Progress of learner mia"));
  EXPECT_THAT(plain, Not(HasSubstr("Mia Example")));
  EXPECT_THAT(plain, Not(HasSubstr("grips hard")));
  const std::string view = report::progressPageHtml(p, {.whole_page = false});
  EXPECT_THAT(view, Not(HasSubstr("<svg")));
  EXPECT_THAT(view, Not(HasSubstr("<h1>")));
  EXPECT_THAT(view, HasSubstr("★ best"));
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
