// The simulated trainee's pace varies from trial to trial, and a study's trials then last as
// long as the trainee takes (the end rule), not a fixed window.

#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "hattr/io/profile_csv.hpp"
#include "hattr/session/study_runner.hpp"
#include "hattr/sim/data_dir.hpp"
#include "hattr/sim/expert.hpp"
#include "hattr/sim/participant.hpp"
#include "hattr/sim/trainee.hpp"
#include "sim/shipped_model.hpp"
#include "support/test_support.hpp"
#include "support/thread_sanitizer.hpp"

namespace hattr::sim {
namespace {

const HapticProfile& loopScript() {
  static const HapticProfile script = expertScript(loadGlyph(defaultDataDir() / "glyphs" / "loop.json"));
  return script;
}

TEST(SimulatedTraineePace, EachTrialHasItsOwnPaceDrawnFromItsSeed) {
  const SubjectTraits traits = populationTraits(test::shippedModel());
  ASSERT_GT(traits.pace_cv, 0.0);
  const std::uint64_t seed = test::testSeed(5);
  SCOPED_TRACE(::testing::Message() << "seed " << seed);
  const SimulatedTrainee trainee(test::shippedModel(), traits, loopScript(), seed);
  // The same trial seed, the same pace; the log of the pace has the model's SD.
  std::vector<double> logs;
  for (std::uint64_t trial = 0; trial < 2000; ++trial) {
    const double pace = trainee.paceFactor(trial);
    ASSERT_EQ(pace, trainee.paceFactor(trial));
    logs.push_back(std::log(pace));
  }
  double mean = 0.0, sq = 0.0;
  for (const double l : logs) mean += l / static_cast<double>(logs.size());
  for (const double l : logs) sq += (l - mean) * (l - mean) / static_cast<double>(logs.size() - 1);
  EXPECT_NEAR(mean, 0.0, 0.01);
  EXPECT_NEAR(std::sqrt(sq), traits.pace_cv, 0.1 * traits.pace_cv);
  // The hand plays the whole plan at that pace.
  const auto hand = trainee.handForTrial(7);
  const auto* script = dynamic_cast<const device::ProfileHandScript*>(hand.get());
  ASSERT_NE(script, nullptr);
  EXPECT_NEAR(script->duration_s(), trainee.duration_s() * trainee.paceFactor(7), 1e-9);
  // Without variability every trial keeps the plan's pace.
  SubjectTraits steady = traits;
  steady.pace_cv = 0.0;
  EXPECT_EQ(SimulatedTrainee(test::shippedModel(), steady, loopScript(), seed).paceFactor(7), 1.0);
}

/// The durations [s] of the trials of a one-subject BASIC study of simulated trainees whose
/// model has `pace_cv`, each ending by the end rule.
std::vector<double> studyTrialDurations(double pace_cv) {
  test::TempDir dir;
  io::writeProfileCsv(loopScript(), dir / "expert.csv", hattr::Overwrite::kReplace);
  test::writeText(dir / "study.json", R"({"name": "pace", "skill": "loop", "experts": {"loop": "expert.csv"},
    "modes": ["basic"], "protocol": {"training_trials": 2, "recall_trials": 2, "rest_s": 0,
    "trial_end": {"pen_up_s": 0.2}}, "world": {"relief": {"kind": "flat"}},
    "subjects": {"count": 1, "participant": "simulated"}})");
  TraineeModel model = test::shippedModel();
  model.pace_cv.value = pace_cv;
  session::StudyDatabase db =
      session::StudyDatabase::create(dir / "s.sqlite", session::loadStudy(dir / "study.json"));
  db = session::StudyDatabase::open(dir / "s.sqlite", session::OpenMode::kRunner);
  session::StudyRunner runner(db, [&model](const session::SubjectRecord& subject, const HapticProfile& expert) {
    return makeSimulatedParticipant(subject, expert, model);
  });
  EXPECT_EQ(runner.run({}), 4);
  std::vector<double> durations;
  for (const auto& t : db.trials()) {
    const HapticProfile p = db.trialProfile(t.id);
    EXPECT_EQ(p.metadata().extra.at("end_reason"), "pen lifted") << "trial " << t.plan.sequence;
    durations.push_back(p.duration_s());
  }
  return durations;
}

TEST(SimulatedTraineePace, AStudysTrialsLastAsLongAsTheTraineeTakes) {
  HATTR_STARTS_NO_THREAD();
  const auto varied = studyTrialDurations(test::shippedModel().pace_cv.value);
  const auto steady = studyTrialDurations(0.0);
  ASSERT_EQ(varied.size(), 4u);
  ASSERT_EQ(steady.size(), 4u);
  const auto spread = [](const std::vector<double>& d) {
    return *std::max_element(d.begin(), d.end()) - *std::min_element(d.begin(), d.end());
  };
  EXPECT_GT(spread(varied), 0.05) << "the pace varies from trial to trial";
  EXPECT_LT(spread(steady), 0.01) << "at a steady pace the trials last the same";
}

}  // namespace
}  // namespace hattr::sim
