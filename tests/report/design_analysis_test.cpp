// The analysis of a design (report::analyzeDesign): every completed trial scored against its
// skill's expert, curves, session and phase cells, retention against the post-test, transfer,
// disturbed trials by the policy, and a study in progress.

#include "hattr/report/design_analysis.hpp"

#include <cmath>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/io/table_csv.hpp"
#include "hattr/session/study_runner.hpp"
#include "support/test_support.hpp"

namespace hattr::report {
namespace {

using ::testing::HasSubstr;

/// An expert profile: a curve (skill "curve") or a line (skill "line").
void writeExpert(const std::filesystem::path& file, const std::string& skill) {
  HapticProfile expert({.subject = "expert", .skill = skill, .nominal_rate_hz = 100.0});
  for (int i = 0; i <= 40; ++i) {
    Sample s;
    s.t_s = i * 0.01;
    s.p_WT = Vec3(0.0005 * i, skill == "curve" ? 0.004 * std::sin(i * 0.15) : 0.0002 * i, 0.0);
    s.f_user_W = Vec3(0.0, 0.0, -1.0 - 0.3 * std::sin(i * 0.2));
    s.pen_down = true;
    expert.append(s);
  }
  io::writeProfileCsv(expert, file);
}

/// Two groups of three scripted subjects: baseline, training, post-test on day 0; retention
/// and transfer to "line" on day 1. `policy`: the disturbed-trial policy.
struct DesignStudy {
  explicit DesignStudy(const std::string& policy, session::RunOptions options = {}) {
    writeExpert(dir / "curve.csv", "curve");
    writeExpert(dir / "line.csv", "line");
    test::writeText(dir / "study.json", fmt::format(R"({{"name": "design", "skill": "curve",
      "experts": {{"curve": "curve.csv", "line": "line.csv"}},
      "protocol": {{"rest_s": 0, "tail_s": 0.05, "disturbed_trials": "{}", "max_repeats": 0}},
      "world": {{"relief": {{"kind": "flat"}}}},
      "groups": [
        {{"name": "g1", "strategies": ["pcontrol"],
          "subjects": {{"count": 3, "prefix": "A", "participant": "script", "options": {{"jitter_mm": 2.0}}}}}},
        {{"name": "g2", "strategies": ["alpha"],
          "subjects": {{"count": 3, "prefix": "B", "participant": "script", "options": {{"jitter_mm": 2.0}}}}}}],
      "sessions": [
        {{"day": 0, "blocks": [{{"phase": "baseline", "trials": 1}}, {{"phase": "training", "strategy": "group", "trials": 2}},
                               {{"phase": "post-test", "trials": 2}}]}},
        {{"day": 1, "blocks": [{{"phase": "retention", "trials": 2}}, {{"phase": "transfer", "skill": "line", "trials": 1}}]}}]}})",
                                                    policy));
    { (void)session::StudyDatabase::create(dir / "s.sqlite", session::loadStudy(dir / "study.json")); }
    session::StudyDatabase db = session::StudyDatabase::open(dir / "s.sqlite", session::OpenMode::kRunner);
    session::StudyRunner(db, session::makeScriptParticipant).run(options);
  }
  test::TempDir dir;
};

double meanOf(const std::vector<double>& v) {
  double sum = 0.0;
  for (const double x : v) sum += x;
  return sum / static_cast<double>(v.size());
}

TEST(DesignAnalysis, ScoresEveryTrialAgainstItsSkillsExpertAndTabulatesTheDesign) {
  DesignStudy study("flag");
  const auto db = session::StudyDatabase::open(study.dir / "s.sqlite", session::OpenMode::kReadOnly);
  const DesignAnalysis a = analyzeDesign(db);
  EXPECT_EQ(a.condition_kind, "group");
  EXPECT_EQ(a.conditions, (std::vector<std::string>{"g1", "g2"}));
  EXPECT_EQ(a.phases, (std::vector<std::string>{"baseline", "training", "post-test", "retention", "transfer"}));
  ASSERT_EQ(a.scores.size(), 6u * 8u);
  EXPECT_EQ(a.trials_pending, 0);

  // Each score is the scorer's on the trial against its own skill's expert.
  for (const DesignTrialScore& s : a.scores) {
    const analysis::TrialScorer scorer(db.expert(s.skill));
    const analysis::TrialScore want = scorer.score(db.trialProfile(s.trial_id));
    ASSERT_EQ(s.shape(), want.shape()) << s.subject << " " << s.phase;
  }
  // A curve point: the mean over g2's subjects of their training trial 2.
  std::vector<double> shapes;
  for (const DesignTrialScore& s : a.scores) {
    if (s.condition == "g2" && s.phase == "training" && s.trial_in_phase == 2) shapes.push_back(s.shape());
  }
  const auto point = std::find_if(a.curves.begin(), a.curves.end(), [](const CurvePoint& p) {
    return p.condition == "g2" && p.phase == "training" && p.trial_in_phase == 2;
  });
  ASSERT_NE(point, a.curves.end());
  EXPECT_EQ(point->shape.subjects, 3);
  EXPECT_NEAR(point->shape.mean, meanOf(shapes), 1e-12);
  EXPECT_TRUE(std::isfinite(point->shape.ci));

  // Retention: each subject's retention mean minus their post-test mean, then the mean.
  ASSERT_EQ(a.retention.size(), 2u);
  const RetentionRow& r = a.retention[0];
  EXPECT_EQ(r.condition, "g1");
  EXPECT_EQ(r.before, "post-test");
  std::vector<double> changes;
  for (const std::string subject : {"A01", "A02", "A03"}) {
    std::vector<double> post, retention;
    for (const DesignTrialScore& s : a.scores) {
      if (s.subject != subject) continue;
      if (s.phase == "post-test") post.push_back(s.shape());
      if (s.phase == "retention") retention.push_back(s.shape());
    }
    changes.push_back(meanOf(retention) - meanOf(post));
  }
  EXPECT_NEAR(r.shape_change.mean, meanOf(changes), 1e-12);
  // ...and each subject's own, as subject_scores.csv has them.
  for (std::size_t k = 0; k < 3; ++k) {
    const std::string subject = fmt::format("A0{}", k + 1);
    const auto own = std::find_if(a.subject_scores.begin(), a.subject_scores.end(), [&](const SubjectScore& x) {
      return x.subject == subject && x.score == "retention-change";
    });
    ASSERT_NE(own, a.subject_scores.end()) << subject;
    EXPECT_NEAR(own->shape, changes[k], 1e-12) << subject;
  }
  EXPECT_EQ(std::count_if(a.subject_scores.begin(), a.subject_scores.end(),
                          [](const SubjectScore& x) { return x.score == "transfer"; }),
            6);
  EXPECT_NEAR(r.shape_change.mean, r.shape_retention.mean - r.shape_before.mean, 1e-9);

  // Transfer: on the second skill.
  ASSERT_EQ(a.transfer.size(), 2u);
  EXPECT_EQ(a.transfer[1].condition, "g2");
  EXPECT_EQ(a.transfer[1].skill, "line");
  EXPECT_EQ(a.transfer[1].shape.subjects, 3);

  // The tables.
  writeDesignCsv(a, study.dir / "out");
  const io::Table scores = io::readTable(study.dir / "out" / "trials.csv");
  EXPECT_EQ(scores.rows.size(), a.scores.size());
  // The long table carries each trial's kinematics as stored with the trial when it ended.
  const auto lifts = scores.numbers("pen_lifts");
  const auto path = scores.numbers("path_length_m");
  for (std::size_t i = 0; i < a.scores.size(); ++i) {
    const HapticProfile profile = db.trialProfile(a.scores[i].trial_id);
    const auto& extra = profile.metadata().extra;
    EXPECT_EQ(fmt::format("{}", lifts[i]), extra.at("kinematics.pen_lifts"));
    EXPECT_EQ(path[i], std::stod(extra.at("kinematics.path_length_m")));
  }
  EXPECT_EQ(io::readTable(study.dir / "out" / "retention.csv").rows.size(), 2u);
  const nlohmann::json json = designAnalysisToJson(a);
  EXPECT_EQ(json["trial_scores"].size(), a.scores.size());
  EXPECT_EQ(json["transfer"][0]["skill"], "line");
}

// A disturbed trial: kept and flagged under "flag", left out under "exclude"; its text, commas
// and all, goes into the CSV as one cell.
TEST(DesignAnalysis, DisturbedTrialsFollowThePolicyAndAStudyInProgressIsAnalyzedSoFar) {
  session::RunOptions stall;
  stall.inject_stall_at_s = [](const session::TrialPlan& plan, int) {
    return plan.subject == "A01" && plan.phase == "training" && plan.index == 1 ? 0.1 : -1.0;
  };
  for (const std::string policy : {"flag", "exclude"}) {
    DesignStudy study(policy, stall);
    const auto db = session::StudyDatabase::open(study.dir / "s.sqlite", session::OpenMode::kReadOnly);
    const DesignAnalysis a = analyzeDesign(db);
    EXPECT_EQ(a.trials_flagged, policy == "flag" ? 1 : 0) << policy;
    EXPECT_EQ(a.trials_excluded, policy == "exclude" ? 1 : 0) << policy;
    EXPECT_EQ(a.scores.size(), policy == "flag" ? 48u : 47u);
    EXPECT_EQ(a.left_out.size(), policy == "flag" ? 0u : 1u);
    writeDesignCsv(a, study.dir / "out");
    // The long table lists every completed trial, an excluded one marked as not analyzed.
    const io::Table t = io::readTable(study.dir / "out" / "trials.csv");
    EXPECT_EQ(t.rows.size(), 48u);
    const auto analyzed = t.text("analyzed");
    EXPECT_EQ(std::count(analyzed.begin(), analyzed.end(), "0"), policy == "flag" ? 0 : 1) << policy;
  }
  // In progress: what is completed is analyzed, and the rest counted.
  session::RunOptions some;
  some.max_trials = 10;
  DesignStudy partial("flag", some);
  const auto db = session::StudyDatabase::open(partial.dir / "s.sqlite", session::OpenMode::kReadOnly);
  const DesignAnalysis a = analyzeDesign(db);
  EXPECT_EQ(a.scores.size(), 10u);
  EXPECT_EQ(a.trials_pending, 38);
  EXPECT_THAT(designConclusions(a).front(), HasSubstr("not finished: 10 of 48 trials"));
  // The paper's analysis refuses a design, saying which to use.
  try {
    (void)analyzeStudy(db);
    ADD_FAILURE() << "analyzeStudy took a design";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("is for the paper's design"));
  }
}

// Each phase's groups compared by a mixed model. Between subjects with random intercepts and
// every subject's trial count equal, the group difference it estimates is the difference of the
// groups' means: a property, not a number copied from the fit.
TEST(DesignAnalysis, EachPhaseComparesItsConditionsByAMixedModelAndTheSummarySaysIt) {
  DesignStudy study("flag");
  const auto db = session::StudyDatabase::open(study.dir / "s.sqlite", session::OpenMode::kReadOnly);
  const DesignAnalysis a = analyzeDesign(db);
  EXPECT_EQ(a.subjects, 6);
  const auto model = std::find_if(a.models.begin(), a.models.end(),
                                  [](const PhaseModel& m) { return m.phase == "training" && m.metric == "shape"; });
  ASSERT_NE(model, a.models.end());
  ASSERT_TRUE(model->skipped.empty()) << model->skipped;
  EXPECT_EQ(model->fit.formula, "shape ~ group + (1 | subject)");
  EXPECT_EQ(model->reference, "g1");
  std::vector<double> g1, g2;
  for (const DesignTrialScore& s : a.scores) {
    if (s.phase == "training") (s.condition == "g1" ? g1 : g2).push_back(s.shape());
  }
  ASSERT_EQ(model->fit.fixed.size(), 2u);
  EXPECT_EQ(model->fit.fixed[1].name, "groupg2");
  EXPECT_NEAR(model->fit.fixed[1].estimate, meanOf(g2) - meanOf(g1), 1e-9);
  EXPECT_LT(model->fit.fixed[1].lower, model->fit.fixed[1].estimate);
  EXPECT_EQ(model->fit.terms.at(0).term, "group");
  // The summary opens with what was compared, and says the test's result for the phase.
  const std::vector<std::string> summary = designSummary(a);
  ASSERT_GE(summary.size(), 3u);
  EXPECT_THAT(summary[0], HasSubstr("Compared: groups (g1 and g2), 6 subjects"));
  EXPECT_THAT(fmt::format("{}", fmt::join(summary, "\n")), HasSubstr("In training,"));
  writeDesignCsv(a, study.dir / "out");
  EXPECT_GT(io::readTable(study.dir / "out" / "models.csv").rows.size(), 4u);
}

// One learner: no between-subject statistics, and the learner's first, best and latest scores.
TEST(DesignAnalysis, OneLearnersStudyShowsTheirProgressWithoutBetweenSubjectStatistics) {
  session::RunOptions only_a01;
  only_a01.only_subject = "A01";
  DesignStudy study("flag", only_a01);
  const auto db = session::StudyDatabase::open(study.dir / "s.sqlite", session::OpenMode::kReadOnly);
  const DesignAnalysis a = analyzeDesign(db);
  EXPECT_EQ(a.subjects, 1);
  EXPECT_TRUE(a.models.empty());
  EXPECT_THAT(a.reason, HasSubstr("one learner"));
  const auto training = std::find_if(a.learner.begin(), a.learner.end(),
                                     [](const LearnerRow& r) { return r.phase == "training"; });
  ASSERT_NE(training, a.learner.end());
  std::vector<double> shapes;
  for (const DesignTrialScore& s : a.scores) {
    if (s.phase == "training") shapes.push_back(s.shape());
  }
  ASSERT_EQ(training->trials, 2);
  EXPECT_EQ(training->first, shapes.front());
  EXPECT_EQ(training->latest, shapes.back());
  EXPECT_EQ(training->best, *std::min_element(shapes.begin(), shapes.end()));
  EXPECT_THAT(designSummary(a).at(0), HasSubstr("One learner practised"));
  const auto html = writeDesignReport(db, a, study.dir / "report");
  EXPECT_TRUE(std::filesystem::exists(html));
}

}  // namespace
}  // namespace hattr::report
