// A study plan's analyses of a replicate's trials (sim::comparisonP): the ANOVA is sim power's to
// the bit, the mixed model agrees with it where both are the same test (balanced trials), and
// the kept trials are the analyzed ones with their recordings' kinematics.
#include "hattr/sim/plan.hpp"

#include <cmath>
#include <map>
#include <random>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/analysis/anova.hpp"
#include "hattr/analysis/kinematics.hpp"
#include "hattr/core/error.hpp"
#include "hattr/report/design_analysis.hpp"
#include "hattr/session/study_database.hpp"
#include "hattr/sim/in_silico.hpp"
#include "support/test_support.hpp"
#include "support/thread_sanitizer.hpp"

namespace hattr::sim {
namespace {

using ::testing::HasSubstr;

/// Equal to the bit, or both NaN.
void expectSame(double a, double b, const std::string& what) {
  if (std::isnan(a) || std::isnan(b)) {
    EXPECT_TRUE(std::isnan(a) && std::isnan(b)) << what << ": " << a << " vs " << b;
  } else {
    EXPECT_EQ(a, b) << what;
  }
}

TEST(PlanAnalysis, KeptTrialsAreTheAnalyzedOnesAndTheirAnovaIsSimPowersToTheBit) {
  HATTR_SKIP_UNDER_THREAD_SANITIZER("a replicate compared with an in-silico study; PowerStudy's tests run one there");
  test::TempDir dir;
  const PowerStudy power({.glyph = test::kStudyGlyph, .training_trials = 1, .recall_trials = 3, .subject_counts = {4},
                          .replicates = 2, .seed = 5, .threads = 2, .keep_trials = true,
                          .kinematic = "mean_speed_m_per_s", .scratch = dir / "scratch"});
  const report::ReplicateOutcome outcome = power.runReplicate(1);
  // 4 subjects × 3 modes × the 2 analyzed of 3 recall trials (the first is left out, as the
  // paper's 10 of 11).
  ASSERT_EQ(outcome.trials.size(), 24u);

  // The ANOVA of the kept trials is the power analysis's own, for the effect and each pair.
  const std::vector<std::string> pairs = power.plan().pairs();
  for (const std::string outcome_name : {"shape", "force"}) {
    const auto& metric = outcome.designs.at(0)[outcome_name == "shape" ? 0 : 1];
    TrialsComparison how{.analysis = PlanAnalysis::kAnova, .outcome = outcome_name};
    expectSame(comparisonP(outcome.trials, how), metric.p_mode, outcome_name + " effect");
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      how.pair_a = pairs[k].substr(pairs[k].find('-') + 1);  // the other way round: Tukey names either
      how.pair_b = pairs[k].substr(0, pairs[k].find('-'));
      expectSame(comparisonP(outcome.trials, how), metric.p_pairs[k], outcome_name + " " + pairs[k]);
    }
  }

  // The same replicate as a study of its own (seed 6): each kept trial is one of its analyzed
  // trials, with its costs and the kinematic measure of its stored (lossless) recording.
  const InSilicoResult alone = runInSilicoStudy({.out_dir = dir / "alone", .glyph = test::kStudyGlyph, .subjects = 4,
                                                 .seed = 6, .training_trials = 1, .recall_trials = 3,
                                                 .write_report = false});
  const session::StudyDatabase db = session::StudyDatabase::open(alone.database, session::OpenMode::kReadOnly);
  std::map<std::tuple<std::string, std::string, int>, const report::TrialCost*> by_cell;
  for (const auto& c : alone.analysis.costs) by_cell[{c.subject, c.mode, c.trial}] = &c;
  int measured = 0;
  for (const auto& t : outcome.trials) {
    const auto found = by_cell.find({t.subject, t.condition, t.trial});
    ASSERT_NE(found, by_cell.end()) << t.subject << " " << t.condition << " " << t.trial;
    EXPECT_EQ(t.shape, found->second->trajectory());
    EXPECT_EQ(t.force, found->second->forceProfile());
    const double speed = analysis::trialKinematics(db.trialProfile(found->second->trial_id)).mean_speed_m_per_s;
    EXPECT_EQ(t.kinematic, speed) << t.subject << " " << t.condition << " " << t.trial;
    if (t.kinematic > 0.0) ++measured;
  }
  EXPECT_EQ(measured, 24) << "every trial wrote something";
}

/// Balanced trials: `subjects` subjects, each in every condition (within) or in one (between),
/// `trials` trials per cell; subject and subject × condition effects large enough that no
/// variance is estimated at zero.
std::vector<report::AnalyzedTrial> balancedTrials(bool between, int subjects, int trials, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const std::vector<std::string> conditions{"A", "B", "C"};
  const std::vector<double> means{0.0, 0.6, 1.0};
  std::vector<report::AnalyzedTrial> out;
  for (int s = 0; s < subjects; ++s) {
    const std::string id = fmt::format("S{:02}", s + 1);
    const double subject = 2.0 * normal(rng);
    for (std::size_t c = 0; c < conditions.size(); ++c) {
      if (between && static_cast<int>(c) != s % 3) continue;
      const double cell = 0.8 * normal(rng);
      for (int k = 1; k <= trials; ++k) {
        const double y = 5.0 + means[c] + subject + cell + normal(rng);
        // The kinematic column: another outcome of the same structure, with its own noise.
        const double kinematic = 1.0 + y + 0.3 * normal(rng);
        out.push_back({static_cast<std::int64_t>(out.size() + 1), id, conditions[c], k, y, -y, kinematic});
      }
    }
  }
  return out;
}

TEST(PlanAnalysis, TheMixedModelIsTheAnovasTestOnBalancedTrials) {
  // Within subjects: y ~ condition + (1 | subject) + (1 | subject:condition) on balanced trials
  // is the split-plot ANOVA (condition against condition:subject), its F and df the same, and a
  // pair's Tukey-adjusted t is Tukey's HSD with that error term. Between groups: y ~ group +
  // (1 | subject) is the one-way ANOVA of the subjects' means. Both hold while no variance is
  // estimated at zero, which the data's large subject and cell effects keep away from.
  for (const bool between : {false, true}) {
    for (std::uint32_t seed = 1; seed <= 6; ++seed) {
      const auto trials = balancedTrials(between, between ? 12 : 8, 4, seed);
      for (const std::string outcome : {"shape", "kinematic-like"}) {
        TrialsComparison anova{.analysis = PlanAnalysis::kAnova, .outcome = "shape", .between_groups = between};
        TrialsComparison mixed = anova;
        mixed.analysis = PlanAnalysis::kMixed;
        if (outcome != "shape") {
          anova.outcome = mixed.outcome = "peak_speed_m_per_s";  // the kinematic column
        }
        for (const auto& [a, b] : std::vector<std::pair<std::string, std::string>>{{"", ""}, {"A", "B"}, {"C", "A"}}) {
          anova.pair_a = mixed.pair_a = a;
          anova.pair_b = mixed.pair_b = b;
          const double p_anova = comparisonP(trials, anova);
          const double p_mixed = comparisonP(trials, mixed);
          ASSERT_TRUE(std::isfinite(p_anova) && std::isfinite(p_mixed)) << seed << " " << a << b;
          EXPECT_NEAR(p_mixed, p_anova, 1e-6 * std::max(p_anova, 1e-3))
              << (between ? "between" : "within") << " seed " << seed << " " << outcome << " pair '" << a << "-"
              << b << "'";
        }
      }
    }
  }
}

TEST(PlanAnalysis, TrialsWithoutAFiniteOutcomeAreLeftOutAndTheNamesAreChecked) {
  std::vector<report::AnalyzedTrial> trials = balancedTrials(false, 8, 4, 3);
  std::vector<report::AnalyzedTrial> finite;
  for (std::size_t k = 0; k < trials.size(); ++k) {
    if (k % 7 == 0) trials[k].kinematic = std::numeric_limits<double>::quiet_NaN();  // e.g. a jerk of nothing
    if (std::isfinite(trials[k].kinematic)) finite.push_back(trials[k]);
  }
  // The mixed model takes the unbalanced rest: the same p as with those trials alone.
  TrialsComparison mixed{.analysis = PlanAnalysis::kMixed, .outcome = "normalized_jerk"};
  const double p = comparisonP(trials, mixed);
  EXPECT_TRUE(std::isfinite(p));
  EXPECT_EQ(p, comparisonP(finite, mixed));
  // The ANOVA needs balanced cells: no p, so the replicate counts as not significant.
  EXPECT_TRUE(std::isnan(comparisonP(trials, {.analysis = PlanAnalysis::kAnova, .outcome = "normalized_jerk"})));

  EXPECT_NO_THROW(checkPlanOutcome("normalized_jerk", "--outcome"));
  try {
    checkPlanOutcome("speed", "--outcome");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("--outcome: expected shape (the trajectory's DTW cost), force (the haptic "
                                    "profile's) or a kinematic measure (duration_s, "));
    EXPECT_THAT(e.what(), HasSubstr("got \"speed\""));
  }
  EXPECT_EQ(parsePlanAnalysis("mixed", "--analysis"), PlanAnalysis::kMixed);
  EXPECT_THROW((void)parsePlanAnalysis("lme", "--analysis"), InputError);
}

}  // namespace
}  // namespace hattr::sim
