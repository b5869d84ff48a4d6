#include "hattr/report/study_report.hpp"

#include <algorithm>
#include <cmath>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/session/study_runner.hpp"
#include "support/test_support.hpp"

namespace hattr::report {
namespace {

using ::testing::HasSubstr;

/// A completed small study: 3 scripted subjects (each trial offset at random), 3 modes,
/// 1 training + 3 recall trials each.
struct CompletedStudy {
  CompletedStudy() {
    HapticProfile expert({.subject = "expert", .skill = "curve", .nominal_rate_hz = 100.0});
    for (int i = 0; i <= 40; ++i) {
      Sample s;
      s.t_s = i * 0.01;
      s.p_WT = Vec3(0.0005 * i, 0.004 * std::sin(i * 0.15), 0.0);
      s.f_user_W = Vec3(0.0, 0.0, -1.0 - 0.3 * std::sin(i * 0.2));
      s.pen_down = true;
      expert.append(s);
    }
    io::writeProfileCsv(expert, dir / "expert.csv");
    test::writeText(dir / "study.json", R"({"name": "report test", "skill": "curve", "experts": {"curve": "expert.csv"},
        "protocol": {"training_trials": 1, "recall_trials": 3, "rest_s": 0, "tail_s": 0.05},
        "world": {"relief": {"kind": "flat"}},
        "subjects": {"count": 3, "participant": "script", "options": {"jitter_mm": 2.0}}})");
    { (void)session::StudyDatabase::create(dir / "s.sqlite", session::loadStudy(dir / "study.json")); }
    session::StudyDatabase db = session::StudyDatabase::open(dir / "s.sqlite", session::OpenMode::kRunner);
    session::StudyRunner(db, session::makeScriptParticipant).run({});
  }
  test::TempDir dir;
};

TEST(StudyAnalysis, CostsEveryRecallTrialAsDirectDtwWould) {
  CompletedStudy study;
  const auto db = session::StudyDatabase::open(study.dir / "s.sqlite", session::OpenMode::kReadOnly);
  const StudyAnalysis a = analyzeStudy(db);
  ASSERT_EQ(a.costs.size(), 3u * 3u * 3u);
  // One trial by hand: the paper's preprocessing, then plain full-matrix DTW on y.
  const TrialCost& c = a.costs[4];
  const HapticProfile expert = db.expert("curve");
  const HapticProfile trial = db.trialProfile(c.trial_id);
  const auto e = analysis::normalize(expert.channel(Channel::kY), analysis::Normalization::kPaper);
  const auto t = analysis::preprocessTrial(trial.channel(Channel::kTime), trial.channel(Channel::kY),
                                           expert.channel(Channel::kTime), analysis::Normalization::kPaper);
  EXPECT_NEAR(c.position[1], analysis::dtwReference(e, t), 1e-9 * std::max(1.0, c.position[1]));
  // The balanced designs: mode × subject with 3 replicates; per mode 3 trials × 3 subjects.
  EXPECT_EQ(a.trajectory.overall.replicates, 3u);
  EXPECT_EQ(a.trajectory.overall.row("mode").error_term, "mode:subject");
  EXPECT_EQ(a.force.per_mode.size(), 3u);
  EXPECT_EQ(a.trajectory.best_mode.size(), 3u);
}

TEST(StudyAnalysis, ConclusionsStateWhatTheNumbersShow) {
  CompletedStudy study;
  const auto db = session::StudyDatabase::open(study.dir / "s.sqlite", session::OpenMode::kReadOnly);
  const StudyAnalysis a = analyzeStudy(db);
  const auto lines = conclusions(a);
  ASSERT_FALSE(lines.empty());
  // The first line names the mode with the lowest mean trajectory cost, and says
  // "significant" exactly when the mode p-value is below α.
  const auto best = std::min_element(a.trajectory.per_mode_stats.begin(), a.trajectory.per_mode_stats.end(),
                                     [](const auto& x, const auto& y) { return x.stats.mean < y.stats.mean; });
  EXPECT_THAT(lines[0], HasSubstr("lowest mean recall cost was with " + best->a_level));
  const bool significant = a.trajectory.overall.row("mode").p < 0.05;
  EXPECT_EQ(lines[0].find("was not significant") == std::string::npos, significant) << lines[0];
}

TEST(StudyReport, WritesASelfContainedHtmlAndMarkdownWithEveryFigure) {
  CompletedStudy study;
  auto db = session::StudyDatabase::open(study.dir / "s.sqlite", session::OpenMode::kReadWrite);
  const StudyAnalysis a = analyzeStudy(db);
  storeAnalysis(db, a);
  ASSERT_TRUE(db.result("analysis").has_value());
  const auto html_path = writeStudyReport(db, a, study.dir / "report");
  writeAnalysisCsv(a, study.dir / "report");
  const std::string html = test::readText(html_path);
  EXPECT_THAT(html, HasSubstr("<svg"));
  EXPECT_THAT(html, HasSubstr("Table 1"));
  EXPECT_THAT(html, HasSubstr("time [s]"));
  EXPECT_THAT(html, HasSubstr("fz [N]"));
  EXPECT_THAT(html, HasSubstr("x [mm]"));
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("src=\"http"), std::string::npos);
  const std::string md = test::readText(study.dir / "report" / "report.md");
  for (const char* fig : {"trajectory_mean_by_trial", "force_variance_per_mode", "profile_fz", "trajectories_ALPHA"}) {
    EXPECT_THAT(md, HasSubstr(std::string("figures/") + fig + ".svg"));
    EXPECT_TRUE(std::filesystem::exists(study.dir / "report" / "figures" / (std::string(fig) + ".svg"))) << fig;
  }
  EXPECT_TRUE(std::filesystem::exists(study.dir / "report" / "table1.csv"));
}

TEST(StudyAnalysis, RefusesAnUnfinishedStudyNamingWhatIsMissing) {
  test::TempDir dir;
  HapticProfile expert({.skill = "c"});
  for (int i = 0; i < 10; ++i) {
    Sample s;
    s.t_s = i * 0.01;
    s.pen_down = true;
    expert.append(s);
  }
  io::writeProfileCsv(expert, dir / "expert.csv");
  test::writeText(dir / "study.json", R"({"name": "u", "skill": "c", "experts": {"c": "expert.csv"},
      "protocol": {"training_trials": 1, "recall_trials": 1}, "subjects": {"count": 2, "participant": "script"}})");
  { (void)session::StudyDatabase::create(dir / "s.sqlite", session::loadStudy(dir / "study.json")); }
  const auto db = session::StudyDatabase::open(dir / "s.sqlite", session::OpenMode::kReadOnly);
  try {
    (void)analyzeStudy(db);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("6 recall trials are not completed yet"));
  }
}

}  // namespace
}  // namespace hattr::report
