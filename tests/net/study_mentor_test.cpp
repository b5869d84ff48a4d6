// Mentored modes inside a study: a simulated expert writes the reference live, tick for tick
// with the trainee over an emulated link, and the trainee's side is stored as the study's trials.

#include <cmath>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/analysis/dtw.hpp"
#include "hattr/core/error.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/net/study_mentor.hpp"
#include "hattr/session/study_runner.hpp"
#include "net/writing_script.hpp"
#include "support/test_support.hpp"
#include "support/thread_sanitizer.hpp"

namespace hattr::net {
namespace {

using ::testing::HasSubstr;

/// The expert writes a figure of eight in 2.4 s, then lifts the pen (so a trial ends 1 s later).
HapticProfile expertWriting() { return test::figureEightThenLift(2.4); }

/// The trainee's hand: the expert's plan 3 mm right and 2 mm down of it.
HapticProfile offsetWriting(const HapticProfile& expert) { return test::offsetScript(expert, Vec3(0.003, -0.002, 0.0)); }

/// A study of the four mentored modes and BASIC, one scripted subject whose pen a coupling can
/// move (a compliant grip), a simulated expert 100 ms away with 5 % loss.
std::string mentoredStudy(const test::TempDir& dir) {
  const HapticProfile expert = expertWriting();
  io::writeProfileCsv(expert, dir / "expert.csv");
  io::writeProfileCsv(offsetWriting(expert), dir / "trainee.csv");
  return R"({
    "name": "mentored", "skill": "eight", "experts": {"eight": "expert.csv"},
    "modes": ["basic", "mentor-observe", "mentor-position", "mentor-force", "mentor-bilateral"],
    "protocol": {"training_trials": 2, "recall_trials": 1, "rest_s": 0, "analyzed_recall_trials": [1]},
    "order": {"kind": "fixed"},
    "mentor": {"expert": "simulated", "round_trip_ms": 100, "loss_percent": 5},
    "device": "sim://pen?hand_stiffness_N_per_m=80",
    "world": {"relief": {"kind": "flat"}},
    "subjects": [{"id": "T1", "participant": "script", "options": {"hand": ")" +
         (dir / "trainee.csv").string() + R"("}}]
  })";
}

/// Runs the study in `db_file` to its end (or `max_trials`) with its simulated mentor.
int runStudy(const std::filesystem::path& db_file, int max_trials = -1) {
  session::StudyDatabase db = session::StudyDatabase::open(db_file, session::OpenMode::kRunner);
  const session::StudyDefinition& study = db.study();
  const auto mentor = makeStudyMentor(study.mentor, db.expert(study.skill),
                                      render::parseWorldConfig(study.world.dump(), "study world"), study.rate_hz);
  session::StudyRunner runner(db, session::makeScriptParticipant);
  return runner.run(session::RunOptions{.max_trials = max_trials, .mentor = mentor.get()});
}

double metaNumber(const HapticProfile& p, const char* key) { return std::stod(p.metadata().extra.at(key)); }

TEST(StudyMentor, MentoredModesAreStudyTrialsThatGuideTheTraineeStablyAt100MsAnd5PercentLoss) {
  HATTR_STARTS_NO_THREAD();
  test::TempDir dir;
  test::writeText(dir / "study.json", mentoredStudy(dir));
  const auto db_file = dir / "study.sqlite";
  (void)session::StudyDatabase::create(db_file, session::loadStudy(dir / "study.json"));
  ASSERT_EQ(runStudy(db_file), 15);

  const session::StudyDatabase db = session::StudyDatabase::open(db_file, session::OpenMode::kReadOnly);
  const HapticProfile expert = db.expert("eight");
  std::map<std::string, double> training_dtw;
  for (const session::TrialRecord& t : db.trials()) {
    ASSERT_EQ(t.status, session::TrialStatus::kCompleted);
    const HapticProfile trial = db.trialProfile(t.id);
    const auto& extra = trial.metadata().extra;
    const std::string mode(guidance::modeName(t.plan.mode));
    EXPECT_EQ(extra.at("study_mode"), mode);
    EXPECT_EQ(extra.at("safety_faults"), "0") << mode;
    EXPECT_FALSE(extra.contains("disturbed")) << mode << ": " << extra.at("disturbed");
    EXPECT_EQ(extra.at("end_reason"), "pen lifted") << mode;
    if (t.plan.phase == session::kPhaseRecall || !guidance::isMentored(t.plan.mode)) {
      // Recall is unassisted (BASIC), as in every mode; no coupling acted.
      EXPECT_FALSE(extra.contains("coupling")) << mode;
      EXPECT_EQ(extra.at("mode"), "BASIC");
    } else {
      EXPECT_EQ(extra.at("mode"), mode);
      EXPECT_EQ(extra.at("coupling"), std::string(couplingName(couplingOfMode(t.plan.mode))));
      EXPECT_THAT(extra.at("mentor_link"), HasSubstr("round trip 100 ms"));
      EXPECT_GT(metaNumber(trial, "peer_packets_received"), 0.9 * static_cast<double>(trial.size()));
      // Bilateral: the two people together got no more energy from the coupling than they put in.
      if (t.plan.mode == guidance::TrainingMode::kMentorBilateral) {
        const double generated = metaNumber(trial, "coupling_energy_out_J") - metaNumber(trial, "coupling_energy_in_J") +
                                 metaNumber(trial, "expert_coupling_energy_out_J") -
                                 metaNumber(trial, "expert_coupling_energy_in_J");
        EXPECT_LE(generated, 1e-9);
      }
    }
    if (t.plan.phase == session::kPhaseTraining && t.plan.index == 2) training_dtw[mode] = test::trajectoryDtw(trial, expert);
  }
  for (const auto& [mode, dtw] : training_dtw) std::printf("%-17s training DTW to the expert %.3f mm\n", mode.c_str(), dtw * 1e3);
  // The live expert's pen guides: position and bilateral bring the trainee's shape to it.
  EXPECT_LT(training_dtw["MENTOR-POSITION"], 0.7 * training_dtw["BASIC"]);
  EXPECT_LT(training_dtw["MENTOR-BILATERAL"], 0.7 * training_dtw["BASIC"]);
  EXPECT_NEAR(training_dtw["MENTOR-OBSERVE"], training_dtw["BASIC"], 0.1 * training_dtw["BASIC"]);
}

TEST(StudyMentor, AMentoredStudyResumedMidwayIsBitIdenticalToOneRunStraight) {
  HATTR_STARTS_NO_THREAD();
  test::TempDir dir;
  test::writeText(dir / "study.json", mentoredStudy(dir));
  const auto study = session::loadStudy(dir / "study.json");
  (void)session::StudyDatabase::create(dir / "straight.sqlite", study);
  (void)session::StudyDatabase::create(dir / "resumed.sqlite", study);
  ASSERT_EQ(runStudy(dir / "straight.sqlite"), 15);
  ASSERT_EQ(runStudy(dir / "resumed.sqlite", 7), 7);  // stops inside MENTOR-POSITION's block
  ASSERT_EQ(runStudy(dir / "resumed.sqlite"), 8);

  const auto straight = session::StudyDatabase::open(dir / "straight.sqlite", session::OpenMode::kReadOnly);
  const auto resumed = session::StudyDatabase::open(dir / "resumed.sqlite", session::OpenMode::kReadOnly);
  const auto a = straight.trials(), b = resumed.trials();
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    const HapticProfile pa = straight.trialProfile(a[i].id), pb = resumed.trialProfile(b[i].id);
    ASSERT_EQ(pa.size(), pb.size()) << "trial " << i;
    for (std::size_t k = 0; k < pa.size(); ++k) {
      ASSERT_EQ(pa.samples()[k].p_WT, pb.samples()[k].p_WT) << "trial " << i << " sample " << k;
      ASSERT_EQ(pa.samples()[k].f_guide_W, pb.samples()[k].f_guide_W) << "trial " << i << " sample " << k;
    }
  }
}

TEST(StudyMentor, AStudyWithMentoredModesNeedsItsMentorAndATrialWithoutOneIsRefused) {
  HATTR_STARTS_NO_THREAD();
  test::TempDir dir;
  test::writeText(dir / "study.json", mentoredStudy(dir));
  (void)session::StudyDatabase::create(dir / "s.sqlite", session::loadStudy(dir / "study.json"));
  session::StudyDatabase db = session::StudyDatabase::open(dir / "s.sqlite", session::OpenMode::kRunner);
  session::StudyRunner runner(db, session::makeScriptParticipant);
  try {
    (void)runner.run({});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("has mentored modes: their training trials need the expert's station"));
  }
  EXPECT_EQ(db.trials().front().status, session::TrialStatus::kPending);  // nothing ran

  // A single trial of a mentored mode without live guidance says what it needs.
  session::TrialEnvironment env("sim://pen", render::WorldConfig{}, 1000.0);
  const HapticProfile expert = expertWriting();
  device::ProfileHandScript hand(expert);
  session::TrialSetup setup{.duration_s = 1.0};
  setup.guidance.mode = guidance::TrainingMode::kMentorPosition;
  try {
    (void)session::runTrial(env, setup, hand);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("mode MENTOR-POSITION: a mentored mode needs an expert's station"));
  }
}

TEST(StudyMentor, ALinkThatNeverComesUpFailsTheTrialBeforeAnythingIsRecorded) {
  HATTR_STARTS_NO_THREAD();
  test::TempDir dir;
  test::writeText(dir / "study.json", mentoredStudy(dir));
  auto study = session::loadStudy(dir / "study.json");
  session::StudyMentor unreachable = study.mentor;
  unreachable.loss = 1.0;  // beyond what a study file accepts: no packet ever arrives
  const auto mentor = makeStudyMentor(unreachable, expertWriting(), render::WorldConfig{}, 1000.0);
  session::TrialEnvironment env("sim://pen", render::WorldConfig{}, 1000.0);
  const HapticProfile expert = expertWriting();
  device::ProfileHandScript hand(expert);
  session::TrialSetup setup{.duration_s = 5.0, .pen_up_end_s = 1.0, .live_guidance = mentor.get()};
  setup.guidance.mode = guidance::TrainingMode::kMentorPosition;
  const session::TrialResult r = session::runTrial(env, setup, hand);
  EXPECT_THAT(r.failure, HasSubstr("the simulated expert's link did not come up during the settle phase"));
  EXPECT_EQ(r.end_reason, "failed");
  EXPECT_TRUE(r.profile.empty());
}

}  // namespace
}  // namespace hattr::net
