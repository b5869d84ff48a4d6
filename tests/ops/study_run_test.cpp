// A study's run as a library call (issue 41): what `hattr study run` and Python's run_study
// both call.

#include "hattr/ops/study_run.hpp"

#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/session/study.hpp"
#include "hattr/session/study_database.hpp"
#include "session/study_fixture.hpp"
#include "support/test_support.hpp"

namespace hattr::ops {
namespace {

// Two scripted subjects, one mode, 1 + 1 trials each: 4 trials.
std::filesystem::path smallStudy(const test::TempDir& dir) {
  session::writeExpert(dir / "expert.csv");
  test::writeText(dir / "study.json", R"({"name": "ops", "skill": "dash", "experts": {"dash": "expert.csv"},
      "modes": ["pcontrol"], "protocol": {"training_trials": 1, "recall_trials": 1, "rest_s": 0},
      "world": {"relief": {"kind": "flat"}},
      "subjects": {"count": 2, "participant": "script", "options": {"jitter_mm": 1.0}}})");
  const auto db = dir / "study.sqlite";
  (void)session::StudyDatabase::create(db, session::loadStudy(dir / "study.json"));
  return db;
}

TEST(StudyRun, RunsWhatIsLeftSayingHowMuchFirstAndEachTrialAfter) {
  test::TempDir dir;
  const auto db = smallStudy(dir);
  int announced = -1;
  int reported = 0;
  const StudyRunResult first = runStudy({.db = db,
                                         .max_trials = 3,
                                         .started = [&](int n) { announced = n; },
                                         .progress = [&](const session::RunProgress&) { ++reported; }});
  EXPECT_EQ(announced, 3);
  EXPECT_EQ(reported, 3);
  EXPECT_EQ(first.trials_to_run, 3);
  EXPECT_EQ(first.trials_run, 3);
  const StudyRunResult rest = runStudy({.db = db});
  EXPECT_EQ(rest.trials_to_run, 1) << "resumed where it stopped";
  EXPECT_EQ(rest.trials_run, 1);
  EXPECT_EQ(rest.toJson(), nlohmann::json({{"trials_to_run", 1}, {"trials_run", 1}, {"waiting", nlohmann::json::array()}}));
  EXPECT_EQ(runStudy({.db = db}).trials_run, 0);
}

TEST(StudyRun, AnUnknownSubjectIsRefused) {
  test::TempDir dir;
  const auto db = smallStudy(dir);
  EXPECT_THROW((void)runStudy({.db = db, .subject = "S99"}), InputError);
}

}  // namespace
}  // namespace hattr::ops
