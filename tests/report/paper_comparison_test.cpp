// The paper's findings as data, and how a study's analysis is set beside them.

#include "hattr/report/paper_comparison.hpp"

#include <fmt/format.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace hattr::report {
namespace {

using ::testing::HasSubstr;

/// A per-mode trial × subject table with the given p-values.
analysis::AnovaTable perModeTable(double p_trial, double p_subject) {
  analysis::AnovaTable t;
  t.rows.push_back({.source = "trial", .p = p_trial});
  t.rows.push_back({.source = "subject", .p = p_subject});
  return t;
}

/// An analysis that says, point by point, what the paper says (section 6, Table 1, section 7).
StudyAnalysis asThePaperFound() {
  StudyAnalysis a;
  for (MetricResult* m : {&a.trajectory, &a.force}) {
    const bool shape = m == &a.trajectory;
    m->per_mode["BASIC"] = perModeTable(0.5, 0.0001);
    m->per_mode["PCONTROL"] = perModeTable(shape ? 0.4 : 0.002, 0.3);
    m->per_mode["ALPHA"] = perModeTable(shape ? 0.6 : 0.008, 0.7);
    m->overall.rows.push_back({.source = "mode", .p = 0.4});
    m->inter_subject = {{"BASIC", 30.0}, {"PCONTROL", 20.0}, {"ALPHA", 10.0}};
    m->per_mode_stats = {{.a_level = "BASIC", .stats = {.mean = 9.0}},
                         {.a_level = "PCONTROL", .stats = {.mean = 8.0}},
                         {.a_level = "ALPHA", .stats = {.mean = 7.0}}};
    for (const auto& row : paperTable1()) {
      m->best_mode[fmt::format("S{:02}", row.person)] = shape ? row.shape : row.haptic_profile;
    }
  }
  return a;
}

session::StudyDefinition paperStudy() {
  session::StudyDefinition s;
  s.skill = "na";
  s.modes = {guidance::TrainingMode::kBasic, guidance::TrainingMode::kPositionControl, guidance::TrainingMode::kForceControl};
  return s;
}

const ComparisonRow& rowNamed(const PaperComparison& c, const std::string& point) {
  for (const auto& r : c.rows) {
    if (r.point == point) return r;
  }
  throw std::runtime_error("no row " + point);
}

TEST(PaperComparison, ThePapersTable1AndFindingsAreAsItsTextGivesThem) {
  // Table 1: shape ALPHA for 7 of 10 subjects; haptic profile ALPHA 3, PCONTROL 4, BASIC 3.
  std::map<std::string, int> shape, haptic;
  for (const auto& r : paperTable1()) {
    ++shape[r.shape];
    ++haptic[r.haptic_profile];
  }
  EXPECT_EQ(paperTable1().size(), 10u);
  EXPECT_EQ(shape, (std::map<std::string, int>{{"ALPHA", 7}, {"BASIC", 2}, {"PCONTROL", 1}}));
  EXPECT_EQ(haptic, (std::map<std::string, int>{{"ALPHA", 3}, {"BASIC", 3}, {"PCONTROL", 4}}));
  // Section 6: significant are the subjects in BASIC (both metrics) and training on the haptic
  // profile in PCONTROL and ALPHA; nothing else.
  std::vector<std::string> significant;
  for (const auto& f : paperAnovaFindings()) {
    if (f.significant) {
      significant.push_back(fmt::format("{} {} {}", f.metric == PaperMetric::kShape ? "shape" : "haptic", f.mode, f.factor));
    }
  }
  EXPECT_THAT(significant, ::testing::UnorderedElementsAre("shape BASIC subject", "haptic BASIC subject",
                                                           "haptic PCONTROL trial", "haptic ALPHA trial"));
  EXPECT_EQ(paperAnovaFindings().size(), 12u);
}

TEST(PaperComparison, AStudyThatFoundWhatThePaperFoundAgreesOnEveryPoint) {
  session::StudyDefinition study = paperStudy();
  const PaperComparison c = compareWithPaper(study, 10, asThePaperFound());
  ASSERT_TRUE(c.applicable);
  EXPECT_TRUE(c.protocol_differences.empty());
  EXPECT_EQ(c.rows.size(), 21u);
  for (const auto& r : c.rows) EXPECT_EQ(r.agreement, Agreement::kAgrees) << r.point << ": " << r.hattr;
}

TEST(PaperComparison, EachPointDiffersWhenTheStudyFoundOtherwise) {
  StudyAnalysis a = asThePaperFound();
  a.force.per_mode["PCONTROL"] = perModeTable(0.2, 0.3);          // no training effect
  a.trajectory.per_mode["ALPHA"] = perModeTable(0.6, 0.01);       // subjects differ
  a.trajectory.overall.rows.front().p = 0.01;                      // mode matters for shape
  a.force.inter_subject = {{"BASIC", 5.0}, {"PCONTROL", 20.0}, {"ALPHA", 10.0}};
  a.trajectory.per_mode_stats[0].stats.mean = 1.0;                 // BASIC best, ALPHA worst
  a.trajectory.best_mode = {{"S01", "BASIC"}, {"S02", "ALPHA"}};  // a tie: no mode most often best
  const PaperComparison c = compareWithPaper(paperStudy(), 10, a);
  for (const char* point :
       {"haptic profile, PCONTROL: effect of training (recall trial)", "shape, ALPHA: difference between subjects",
        "shape: effect of the training mode (mode × subject ANOVA)", "haptic profile: least inter-subject variance",
        "shape: best mode (lowest mean recall cost)", "shape: worst mode (highest mean recall cost)",
        "shape: subjects whose best mode it is"}) {
    EXPECT_EQ(rowNamed(c, point).agreement, Agreement::kDiffers) << point << ": " << rowNamed(c, point).hattr;
  }
  EXPECT_EQ(c.count(Agreement::kDiffers), 7);
  EXPECT_EQ(rowNamed(c, "haptic profile, PCONTROL: effect of training (recall trial)").hattr, "not significant (p = 0.200)");
  EXPECT_EQ(rowNamed(c, "haptic profile: least inter-subject variance").hattr, "BASIC (BASIC 5, PCONTROL 20, ALPHA 10)");
}

TEST(PaperComparison, WhatTheStudyCouldNotComputeIsNotMeasuredAndTheProtocolsDifferencesAreListed) {
  StudyAnalysis a = asThePaperFound();
  a.trajectory.per_mode.erase("BASIC");  // e.g. a single analyzed recall trial
  session::StudyDefinition study = paperStudy();
  study.protocol.training_trials = 3;
  study.protocol.recall_trials = 4;
  study.protocol.recall.show_reference = true;
  const PaperComparison c = compareWithPaper(study, 4, a);
  EXPECT_EQ(rowNamed(c, "shape, BASIC: effect of training (recall trial)").agreement, Agreement::kNotMeasured);
  EXPECT_EQ(c.count(Agreement::kNotMeasured), 2);
  EXPECT_THAT(c.protocol_differences,
              ::testing::ElementsAre("4 subjects (the paper: 10)", "3 training trials per mode (the paper: 11)",
                                     "4 recall trials per mode (the paper: 11)",
                                     "3 recall trials analyzed per mode (the paper: 10)",
                                     "recall with assistance or with the reference shown (the paper: neither)"));
  const auto text = comparisonText(c);
  EXPECT_THAT(text.front(), HasSubstr("19 points agree, 0 differ, 2 not measured"));
}

TEST(PaperComparison, AStudyWithoutThePapersThreeModesIsNotSetBesideIt) {
  session::StudyDefinition study = paperStudy();
  study.modes.pop_back();
  const PaperComparison c = compareWithPaper(study, 10, asThePaperFound());
  EXPECT_FALSE(c.applicable);
  EXPECT_TRUE(c.rows.empty());
  EXPECT_THAT(comparisonText(c).front(), HasSubstr("not set beside the paper"));
}

// Issue 35: a signature study in the paper's three modes is not the paper's experiment either.
TEST(PaperComparison, AStudyOfAnotherSkillIsNotSetBesideIt) {
  session::StudyDefinition study = paperStudy();
  study.skill = "U1S1";
  EXPECT_FALSE(compareWithPaper(study, 10, asThePaperFound()).applicable);
  study.skill = "ந";
  EXPECT_TRUE(compareWithPaper(study, 10, asThePaperFound()).applicable);
}

}  // namespace
}  // namespace hattr::report
