#include "hattr/report/study_report.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/io/table_csv.hpp"
#include "hattr/analysis/trial_score.hpp"
#include "hattr/report/design_analysis.hpp"
#include "hattr/session/study_runner.hpp"
#include "hattr/session/subject_trials.hpp"
#include "support/test_support.hpp"
#include "support/thread_sanitizer.hpp"

namespace hattr::report {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;
using ::testing::StartsWith;

/// A completed small study: 3 scripted subjects (each trial offset at random), 3 modes,
/// 1 training + 3 recall trials each.
struct CompletedStudy {
  /// `protocol_extra`: more protocol keys (JSON, each followed by a comma); `options`: the run's.
  explicit CompletedStudy(const std::string& protocol_extra = "", session::RunOptions options = {},
                          const session::StoreOptions& store = {}) {
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
        "protocol": {)" + protocol_extra + R"("training_trials": 1, "recall_trials": 3, "rest_s": 0, "tail_s": 0.05},
        "world": {"relief": {"kind": "flat"}},
        "subjects": {"count": 3, "participant": "script", "options": {"jitter_mm": 2.0}}})");
    { (void)session::StudyDatabase::create(dir / "s.sqlite", session::loadStudy(dir / "study.json")); }
    session::StudyDatabase db = session::StudyDatabase::open(dir / "s.sqlite", session::OpenMode::kRunner, store);
    session::StudyRunner(db, session::makeScriptParticipant).run(options);
  }
  test::TempDir dir;
};

/// Every channel of every sample the same to the bit.
void expectSameSamples(const HapticProfile& a, const HapticProfile& b, const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (const Channel c : {Channel::kTime, Channel::kX, Channel::kY, Channel::kZ, Channel::kFx, Channel::kFy, Channel::kFz}) {
    EXPECT_EQ(a.channel(c), b.channel(c)) << what << " channel " << static_cast<int>(c);
  }
}

/// A profile's times and one channel within its writing span (as the scorer takes them).
std::pair<std::vector<double>, std::vector<double>> spanOf(const HapticProfile& p, Channel channel) {
  const analysis::TimeSpan span = analysis::writingSpan(p);
  const std::vector<double> all_t = p.channel(Channel::kTime);
  const std::vector<double> all_v = p.channel(channel);
  std::vector<double> t, v;
  for (std::size_t i = 0; i < all_t.size(); ++i) {
    if (all_t[i] < span.begin_s || all_t[i] > span.end_s) continue;
    t.push_back(all_t[i]);
    v.push_back(all_v[i]);
  }
  return {t, v};
}

TEST(StudyAnalysis, CostsTheAnalyzedRecallTrialsAsDirectDtwWould) {
  CompletedStudy study;
  const auto db = session::StudyDatabase::open(study.dir / "s.sqlite", session::OpenMode::kReadOnly);
  const StudyAnalysis a = analyzeStudy(db);
  // 10 of 11 in the paper; here 2 of 3: the first recall trial of each mode is left out.
  EXPECT_EQ(a.analyzed_recall_trials, (std::vector<int>{2, 3}));
  ASSERT_EQ(a.costs.size(), 3u * 3u * 2u);
  for (const auto& c : a.costs) EXPECT_NE(c.trial, 1);
  // One trial by hand: its writing span, the paper's preprocessing, then plain full-matrix DTW.
  const TrialCost& c = a.costs[4];
  const HapticProfile expert = db.expert("curve");
  const HapticProfile trial = db.trialProfile(c.trial_id);
  const auto by_hand = [&](Channel channel) {
    const auto [et, ev] = spanOf(expert, channel);
    const auto [tt, tv] = spanOf(trial, channel);
    const auto e = analysis::normalize(ev, analysis::Normalization::kPaper);
    const auto t = analysis::preprocessTrial(tt, tv, et, analysis::Normalization::kPaper);
    return analysis::dtwReference(e, t);
  };
  EXPECT_NEAR(c.score.y, by_hand(Channel::kY), 1e-9 * std::max(1.0, c.score.y));
  EXPECT_NEAR(c.score.fz, by_hand(Channel::kFz), 1e-9 * std::max(1.0, c.score.fz));
  // The shape is the paper plane: x + y, never z.
  EXPECT_DOUBLE_EQ(c.trajectory(), c.score.x + c.score.y);
  EXPECT_DOUBLE_EQ(c.forceProfile(), c.score.fx + c.score.fy + c.score.fz);
  // The balanced designs: mode × subject with 2 replicates; per mode 2 trials × 3 subjects.
  EXPECT_EQ(a.trajectory.overall.replicates, 2u);
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

TEST(StudyReport, EveryInlineFigureClipsWithItsOwnRectangle) {
  // One page holds every figure inline: a clip-path id shared by two figures made the browser
  // clip all of them with the first one's rectangle (issue 18).
  CompletedStudy study;
  auto db = session::StudyDatabase::open(study.dir / "s.sqlite", session::OpenMode::kReadWrite);
  const StudyAnalysis a = analyzeStudy(db);
  const std::string html = test::readText(writeStudyReport(db, a, study.dir / "report"));
  std::vector<std::string> ids;
  for (auto at = html.find("<clipPath id=\""); at != std::string::npos; at = html.find("<clipPath id=\"", at + 1)) {
    const auto begin = at + std::string("<clipPath id=\"").size();
    ids.push_back(html.substr(begin, html.find('"', begin) - begin));
  }
  ASSERT_GE(ids.size(), 10u);
  for (const std::string& id : ids) {
    EXPECT_EQ(std::count(ids.begin(), ids.end(), id), 1) << "clip-path id used by several figures: " << id;
    EXPECT_NE(html.find("clip-path=\"url(#" + id + ")\""), std::string::npos) << id;
  }
  // The same figure gets the same id on every run: a report is reproducible byte for byte.
  EXPECT_EQ(test::readText(writeStudyReport(db, a, study.dir / "report-again")), html);
}

/// Analyzes `study` and writes its report into study.dir / "report".
StudyAnalysis writeReportOf(const CompletedStudy& study) {
  const auto db = session::StudyDatabase::open(study.dir / "s.sqlite", session::OpenMode::kReadOnly);
  StudyAnalysis a = analyzeStudy(db);
  (void)writeStudyReport(db, a, study.dir / "report");
  return a;
}

/// Whether `a`, `b` and `c` all occur in `text`, first ones in that order.
bool inOrder(const std::string& text, const std::string& a, const std::string& b, const std::string& c) {
  const auto pa = text.find(a), pb = text.find(b), pc = text.find(c);
  return pa != std::string::npos && pb != std::string::npos && pc != std::string::npos && pa < pb && pb < pc;
}

TEST(StudyReport, ModesComeInTheStudysOrderEverywhere) {
  CompletedStudy study;  // modes: the paper's BASIC, PCONTROL, ALPHA
  (void)writeReportOf(study);
  const std::string html = test::readText(study.dir / "report" / "report.html");
  EXPECT_TRUE(inOrder(html, "<p>BASIC:</p>", "<p>PCONTROL:</p>", "<p>ALPHA:</p>"));  // the per-mode ANOVA tables
  for (const char* figure : {"trajectory_mean_by_trial", "force_mean_per_mode", "force_variance_per_mode", "profile_fz"}) {
    const std::string svg = test::readText(study.dir / "report" / "figures" / (std::string(figure) + ".svg"));
    EXPECT_TRUE(inOrder(svg, ">BASIC<", ">PCONTROL<", ">ALPHA<")) << figure;
  }
}

/// The error bars' pixel half-heights in an SVG written by the report (each "<path d=...").
std::vector<double> whiskerHeights(const std::string& svg) {
  std::vector<double> out;
  for (auto at = svg.find("<path d=\"M"); at != std::string::npos; at = svg.find("<path d=\"M", at + 1)) {
    double x = 0, y_low = 0, y_high = 0;
    if (std::sscanf(svg.c_str() + at, "<path d=\"M%lf,%lfV%lf", &x, &y_low, &y_high) == 3) out.push_back((y_low - y_high) / 2);
  }
  return out;
}

TEST(StudyReport, MeansCarryTheirConfidenceIntervalsOverSubjects) {
  CompletedStudy study;
  const StudyAnalysis a = writeReportOf(study);
  // One error bar per mode on the bars, one per mode and recall trial on the lines.
  const std::string bars = test::readText(study.dir / "report" / "figures" / "trajectory_mean_per_mode.svg");
  const std::string lines = test::readText(study.dir / "report" / "figures" / "trajectory_mean_by_trial.svg");
  ASSERT_EQ(whiskerHeights(bars).size(), 3u);
  EXPECT_EQ(whiskerHeights(lines).size(), 3u * 2u);  // analyzed recall trials 2 and 3
  // Their lengths are in proportion to t(0.975, subjects - 1) · sd / √n of the subjects' means.
  std::vector<double> expected;
  for (const std::string mode : {"BASIC", "PCONTROL", "ALPHA"}) {
    std::map<std::string, std::vector<double>> by_subject;
    for (const auto& c : a.costs) {
      if (c.mode == mode) by_subject[c.subject].push_back(c.trajectory());
    }
    std::vector<double> means;
    for (const auto& [s, v] : by_subject) means.push_back((v[0] + v[1]) / 2);
    const double m = (means[0] + means[1] + means[2]) / 3;
    double ss = 0;
    for (const double x : means) ss += (x - m) * (x - m);
    expected.push_back(4.302652729749462 * std::sqrt(ss / 2 / 3));
  }
  const std::vector<double> drawn = whiskerHeights(bars);
  ASSERT_GT(drawn[0], 2.0);  // pixels: long enough to compare
  for (std::size_t k = 1; k < 3; ++k) {
    const double ratio = expected[k] / expected[0];
    EXPECT_NEAR(drawn[k] / drawn[0], ratio, 0.03 * ratio + 0.15 / drawn[0]) << k;  // SVG coordinates have 0.1 px
  }
}

TEST(StudyReport, ShowsTheInteractionAndOneSubjectOnTwoOccasions) {
  CompletedStudy study;
  (void)writeReportOf(study);
  const std::string interaction = test::readText(study.dir / "report" / "figures" / "force_mode_by_subject.svg");
  std::size_t subject_lines = 0;
  for (auto at = interaction.find("<polyline fill=\"none\" stroke=\"#9a9a9a\""); at != std::string::npos;
       at = interaction.find("<polyline fill=\"none\" stroke=\"#9a9a9a\"", at + 1)) {
    ++subject_lines;
  }
  EXPECT_EQ(subject_lines, 3u);
  EXPECT_THAT(interaction, HasSubstr("mode (1 = BASIC, 2 = PCONTROL, 3 = ALPHA)"));
  const std::string occasions = test::readText(study.dir / "report" / "figures" / "profile_two_occasions.svg");
  EXPECT_THAT(occasions, HasSubstr("BASIC recall trials 2 and 3"));
  EXPECT_THAT(occasions, HasSubstr(">recall trial 2<"));
  EXPECT_THAT(occasions, HasSubstr(">recall trial 3<"));
}

TEST(StudyAnalysis, ConclusionsSayWhichWayTheRecallTrialsWent) {
  // A significant trial effect with costs rising is forgetting, not learning; falling is the other.
  StudyAnalysis a;
  a.trajectory.metric = "trajectory";
  a.force.metric = "force";
  a.trajectory.per_mode["BASIC"].rows.push_back({.source = "trial", .p = 0.01});
  a.trajectory.mean_by_trial["BASIC"] = {10.0, 11.0, 12.5};
  a.force.per_mode["ALPHA"].rows.push_back({.source = "trial", .p = 0.02});
  a.force.mean_by_trial["ALPHA"] = {9.0, 8.0, 7.0};
  a.force.per_mode["PCONTROL"].rows.push_back({.source = "trial", .p = 0.2});
  a.force.mean_by_trial["PCONTROL"] = {9.0, 10.0, 11.0};
  const auto lines = conclusions(a);
  const std::string text = fmt::format("{}", fmt::join(lines, "\n"));
  EXPECT_THAT(text, HasSubstr("trajectory (shape) metric in: BASIC (p = 0.010, +1.25 per trial: costs rose over the recall "
                              "trials, forgetting or fatigue, not learning)"));
  EXPECT_THAT(text, HasSubstr("haptic-profile (force) metric in: ALPHA (p = 0.020, -1 per trial: costs fell over the recall trials)"));
  EXPECT_THAT(text, Not(HasSubstr("PCONTROL (")));
}

TEST(StudyAnalysis, ConclusionsNameTheModesInTheStudysOrder) {
  // The paper's order (BASIC, PCONTROL, ALPHA), not the alphabet's, when the analysis knows it.
  StudyAnalysis a;
  a.trajectory.metric = "trajectory";
  a.force.metric = "force";
  for (const char* mode : {"ALPHA", "BASIC", "PCONTROL"}) {
    a.trajectory.per_mode[mode].rows.push_back({.source = "trial", .p = 0.01});
    a.trajectory.mean_by_trial[mode] = {10.0, 9.0};
  }
  const auto text = [&a] { return fmt::format("{}", fmt::join(conclusions(a), "\n")); };
  EXPECT_TRUE(inOrder(text(), "ALPHA (", "BASIC (", "PCONTROL (")) << text();
  a.modes = {"BASIC", "PCONTROL", "ALPHA"};
  EXPECT_TRUE(inOrder(text(), "BASIC (", "PCONTROL (", "ALPHA (")) << text();
}

/// An expert of skill "c" in `dir`: `samples` pen-down samples 10 ms apart, a wave along x.
void writeWaveExpert(const std::filesystem::path& dir, int samples) {
  HapticProfile expert({.skill = "c"});
  for (int i = 0; i < samples; ++i) {
    Sample s;
    s.t_s = i * 0.01;
    s.p_WT = Vec3(0.0005 * i, 0.003 * std::sin(i * 0.2), 0.0);
    s.f_user_W = Vec3(0.0, 0.0, -1.0);
    s.pen_down = true;
    expert.append(s);
  }
  io::writeProfileCsv(expert, dir / "expert.csv");
}

TEST(StudyAnalysis, RefusesAnUnfinishedStudyNamingWhatIsMissing) {
  test::TempDir dir;
  writeWaveExpert(dir.path(), 10);
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

// The report's choice: a paper's study missing one recall trial cannot take the balanced ANOVA,
// so it gets the design's analysis: each phase's strategies by a mixed model, subjects and each
// subject's strategy random (replicated within subjects), the reason said.
/// A paper's study in `dir` (2 modes, 2 training and 3 recall trials each, scripted subjects),
/// run for `max_trials` trials (-1: all).
void runSmallPapersStudy(const test::TempDir& dir, int subjects, int max_trials) {
  writeWaveExpert(dir.path(), 40);
  test::writeText(dir / "study.json", fmt::format(R"({{"name": "u", "skill": "c", "experts": {{"c": "expert.csv"}},
      "modes": ["basic", "pcontrol"], "world": {{"relief": {{"kind": "flat"}}}},
      "protocol": {{"training_trials": 2, "recall_trials": 3, "rest_s": 0, "tail_s": 0.05}},
      "subjects": {{"count": {}, "participant": "script", "options": {{"jitter_mm": 2.0}}}}}})",
                                                  subjects));
  { (void)session::StudyDatabase::create(dir / "s.sqlite", session::loadStudy(dir / "study.json")); }
  session::StudyDatabase db = session::StudyDatabase::open(dir / "s.sqlite", session::OpenMode::kRunner);
  session::RunOptions options;
  options.max_trials = max_trials;
  session::StudyRunner(db, session::makeScriptParticipant).run(options);
}

TEST(StudyAnalysis, AnIncompletePapersStudyIsAnalyzedByMixedModelsAndSaysWhy) {
  test::TempDir dir;
  runSmallPapersStudy(dir, 3, 3 * 2 * 5 - 1);  // the last recall trial is not run
  const auto db = session::StudyDatabase::open(dir / "s.sqlite", session::OpenMode::kReadOnly);
  const AnalysisChoice choice = chooseAnalysis(db);
  EXPECT_FALSE(choice.balanced);
  EXPECT_THAT(choice.reason, HasSubstr("not complete"));
  EXPECT_THAT(choice.reason, HasSubstr("1 recall trial is not completed"));
  const DesignAnalysis a = analyzeDesign(db);
  EXPECT_EQ(a.condition_kind, "strategy");
  // 29 trials completed; the recall trials analyzed are the paper's (2 and 3 of 3), so each
  // subject's recall trial 1 in each mode is left out of the tables and the models.
  EXPECT_EQ(a.scores.size(), 29u - 6u);
  ASSERT_EQ(a.left_out.size(), 6u);
  for (const DesignTrialScore& s : a.left_out) {
    EXPECT_EQ(s.phase, "recall");
    EXPECT_EQ(s.trial, 1);
    EXPECT_THAT(s.left_out, HasSubstr("analyzed_recall_trials"));
  }
  for (const CurvePoint& c : a.curves) EXPECT_FALSE(c.phase == "recall" && c.trial_in_phase == 1);
  const auto recall = std::find_if(a.models.begin(), a.models.end(),
                                   [](const PhaseModel& m) { return m.phase == "recall" && m.metric == "shape"; });
  ASSERT_NE(recall, a.models.end());
  ASSERT_TRUE(recall->skipped.empty()) << recall->skipped;
  EXPECT_EQ(recall->fit.formula, "shape ~ strategy + (1 | subject) + (1 | subject:strategy)");
  EXPECT_EQ(recall->fit.observations, 3u * 2u * 2u - 1u);
  EXPECT_EQ(recall->fit.fixed.at(1).name, "strategyPCONTROL");
  // The long table keeps every completed trial and says which the analysis took.
  writeDesignCsv(a, dir / "out");
  const io::Table t = io::readTable(dir / "out" / "trials.csv");
  ASSERT_EQ(t.rows.size(), 29u);
  const auto analyzed = t.text("analyzed");
  const auto phase = t.text("phase");
  const auto trial = t.text("trial");
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    EXPECT_EQ(analyzed[r], phase[r] == "recall" && trial[r] == "1" ? "0" : "1") << "row " << r;
  }
  EXPECT_EQ(designAnalysisToJson(a)["trials_left_out"].size(), 6u);
}

// The design's analysis reads the trial records once: a trial another station completes while it
// scores does not make its choice of analysis disagree with its counts.
TEST(StudyAnalysis, TheDesignsAnalysisJudgesOneSnapshotOfTheTrials) {
  test::TempDir dir;
  runSmallPapersStudy(dir, 3, 3 * 2 * 5 - 1);  // the last recall trial is not run
  const auto db = session::StudyDatabase::open(dir / "s.sqlite", session::OpenMode::kReadOnly);
  bool ran = false;
  AnalysisOptions options;
  options.progress = [&](int, int) {
    if (ran) return;
    ran = true;  // another station completes the last trial now
    session::StudyDatabase station = session::StudyDatabase::open(dir / "s.sqlite", session::OpenMode::kRunner);
    EXPECT_EQ(session::StudyRunner(station, session::makeScriptParticipant).run({}), 1);
  };
  const DesignAnalysis a = analyzeDesign(db, options);
  ASSERT_TRUE(ran);
  EXPECT_EQ(a.trials_pending, 1);
  EXPECT_THAT(a.reason, HasSubstr("not complete")) << "the choice was made from a later read than the counts";
  EXPECT_TRUE(chooseAnalysis(db).balanced) << "read again, the study is complete";
}

// A complete paper's study keeps the balanced ANOVA, and its long table has every trial with
// its kinematics, the recall trials (scored by the balanced analysis) included.
TEST(StudyAnalysis, ACompletePapersStudysLongTableHasEveryTrialsKinematics) {
  test::TempDir dir;
  runSmallPapersStudy(dir, 2, -1);
  const auto db = session::StudyDatabase::open(dir / "s.sqlite", session::OpenMode::kReadOnly);
  ASSERT_TRUE(chooseAnalysis(db).balanced) << chooseAnalysis(db).reason;
  const StudyAnalysis balanced = analyzeStudy(db);
  writeTrialsCsv(db, balanced, {}, dir / "trials.csv");
  const io::Table t = io::readTable(dir / "trials.csv");
  ASSERT_EQ(t.rows.size(), 2u * 2u * 5u);
  const auto phases = t.text("phase");
  const auto lifts = t.text("pen_lifts");
  const auto shape = t.text("shape");
  const auto trial = t.text("trial");
  const auto analyzed = t.text("analyzed");
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    EXPECT_FALSE(lifts[r].empty()) << "row " << r << " (" << phases[r] << ")";
    EXPECT_FALSE(shape[r].empty()) << "row " << r;
    // The balanced analysis takes recall trials 2 and 3; the first is listed, not analyzed.
    EXPECT_EQ(analyzed[r], phases[r] == "recall" && trial[r] == "1" ? "0" : "1") << "row " << r;
  }
}

/// A 30 ms host stall, 0.2 s into the first attempt of S01's recall trial 2 in every mode.
session::RunOptions stallInS01Recall2() {
  session::RunOptions options;
  options.inject_stall_at_s = [](const session::TrialPlan& plan, int attempt) {
    return plan.subject == "S01" && plan.phase == session::kPhaseRecall && plan.index == 2 && attempt == 0 ? 0.2 : -1.0;
  };
  return options;
}

std::vector<session::TrialRecord> s01Recall2(const session::StudyDatabase& db) {
  std::vector<session::TrialRecord> out;
  for (const auto& t : db.trials("S01")) {
    if (t.plan.phase == session::kPhaseRecall && t.plan.index == 2) out.push_back(t);
  }
  return out;
}

TEST(DisturbedTrials, RepeatKeepsTheDisturbedAttemptAndAnalyzesTheCleanOne) {
  CompletedStudy study("", stallInS01Recall2());  // "repeat" is the default
  const auto db = session::StudyDatabase::open(study.dir / "s.sqlite", session::OpenMode::kReadOnly);
  const auto trials = s01Recall2(db);
  ASSERT_EQ(trials.size(), 3u);
  for (const auto& t : trials) {
    EXPECT_EQ(t.disturbed, "");
    EXPECT_EQ(t.disturbed_attempts, 1);
    EXPECT_EQ(t.attempts, 2);
    EXPECT_EQ(db.trialProfile(t.id).metadata().extra.at("loop_stalls"), "0");
  }
  const StudyAnalysis a = analyzeStudy(db);
  EXPECT_TRUE(a.flagged.empty());
  EXPECT_EQ(a.costs.size(), 3u * 3u * 2u);
}

TEST(DisturbedTrials, FlagKeepsThemInTheAnalysisAndTheReportListsThem) {
  CompletedStudy study(R"("disturbed_trials": "flag",)", stallInS01Recall2());
  auto db = session::StudyDatabase::open(study.dir / "s.sqlite", session::OpenMode::kReadWrite);
  for (const auto& t : s01Recall2(db)) {
    // The 30 ms stall zeroed the force while the hand pressed: the pen sank through the paper,
    // and the recording says so too (issue 38).
    EXPECT_THAT(t.disturbed, StartsWith("1 stall (force zeroed) · the pen "));
    EXPECT_THAT(t.disturbed, HasSubstr(" mm under the paper at 0.2"));
    EXPECT_EQ(t.disturbed_attempts, 0);
    const HapticProfile p = db.trialProfile(t.id);
    EXPECT_EQ(p.metadata().extra.at("loop_stalls"), "1");
    EXPECT_EQ(p.metadata().extra.at("disturbed"), t.disturbed);
    EXPECT_EQ(p.metadata().extra.count("physical_penetration"), 1u);
  }
  const StudyAnalysis a = analyzeStudy(db);
  ASSERT_EQ(a.flagged.size(), 3u);
  for (const auto& f : a.flagged) EXPECT_TRUE(f.analyzed);
  EXPECT_EQ(a.costs.size(), 3u * 3u * 2u);
  const auto html = test::readText(writeStudyReport(db, a, study.dir / "report"));
  EXPECT_THAT(html, HasSubstr("Disturbed trials"));
  EXPECT_THAT(html, HasSubstr("1 stall (force zeroed)"));
}

TEST(StoredCosts, ReadBackWhatTheStoredAnalysisCostedTrialByTrial) {
  CompletedStudy study(R"("disturbed_trials": "flag",)", stallInS01Recall2());
  auto db = session::StudyDatabase::open(study.dir / "s.sqlite", session::OpenMode::kReadWrite);
  EXPECT_TRUE(storedCosts(db).empty());  // nothing stored yet
  const StudyAnalysis a = analyzeStudy(db);
  storeAnalysis(db, a);
  const std::vector<TrialCost> back = storedCosts(db);
  ASSERT_EQ(back.size(), a.costs.size());
  int disturbed = 0;
  for (std::size_t i = 0; i < back.size(); ++i) {
    const TrialCost& want = a.costs[i];
    const TrialCost& got = back[i];
    EXPECT_EQ(got.trial_id, want.trial_id);
    EXPECT_EQ(got.subject, want.subject);
    EXPECT_EQ(got.mode, want.mode);
    EXPECT_EQ(got.trial, want.trial);
    EXPECT_EQ(got.disturbed, want.disturbed);
    disturbed += got.disturbed.empty() ? 0 : 1;
    // JSON keeps a double to the bit.
    const std::array<std::pair<double, double>, 6> channels{{{got.score.x, want.score.x},
                                                              {got.score.y, want.score.y},
                                                              {got.score.z, want.score.z},
                                                              {got.score.fx, want.score.fx},
                                                              {got.score.fy, want.score.fy},
                                                              {got.score.fz, want.score.fz}}};
    for (const auto& [g, w] : channels) EXPECT_EQ(g, w) << "trial " << got.trial_id;
  }
  EXPECT_EQ(disturbed, 3);

  db.putResult("analysis", R"({"recall_costs": [{"trial_id": 1}]})");
  try {
    (void)storedCosts(db);
    ADD_FAILURE() << "a stored analysis without the costs' fields was read";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("the study's stored analysis (results key \"analysis\"): recall_costs[0]:"));
  }
  db.putResult("analysis", R"({"recall_costs": 3})");
  try {
    (void)storedCosts(db);
    ADD_FAILURE() << "recall_costs that is no array was read";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("expected an object with an array \"recall_costs\""));
  }
  db.putResult("analysis", "{not json");
  try {
    (void)storedCosts(db);
    ADD_FAILURE() << "a stored analysis that is not JSON was read";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("not JSON"));
  }
}

TEST(DisturbedTrials, ExcludeReplacesThemWithTheSpareRecallTrial) {
  CompletedStudy study(R"("disturbed_trials": "exclude",)", stallInS01Recall2());
  const auto db = session::StudyDatabase::open(study.dir / "s.sqlite", session::OpenMode::kReadOnly);
  const StudyAnalysis a = analyzeStudy(db);
  ASSERT_EQ(a.flagged.size(), 3u);
  for (const auto& f : a.flagged) EXPECT_FALSE(f.analyzed);
  // Still balanced: S01's recall trial 1 (the spare) stands in for trial 2 in each mode.
  EXPECT_EQ(a.costs.size(), 3u * 3u * 2u);
  ASSERT_EQ(a.spares_used.size(), 3u);
  for (const auto& t : db.trials("S01")) {
    const bool spare = std::find(a.spares_used.begin(), a.spares_used.end(), t.id) != a.spares_used.end();
    EXPECT_EQ(spare, t.plan.phase == session::kPhaseRecall && t.plan.index == 1) << t.id;
  }
  EXPECT_EQ(a.trajectory.overall.replicates, 2u);
}

// The fallback takes the recall trials the paper's analysis would: under "exclude" a disturbed
// one is left out and the spare stands in for it, in its place on the recall curve.
TEST(StudyAnalysis, AnIncompletePapersStudysFallbackUsesTheSpareForAnExcludedTrial) {
  session::RunOptions options = stallInS01Recall2();
  options.max_trials = 3 * 3 * 4 - 1;  // the last trial is not run
  CompletedStudy study(R"("disturbed_trials": "exclude",)", options);
  const auto db = session::StudyDatabase::open(study.dir / "s.sqlite", session::OpenMode::kReadOnly);
  ASSERT_FALSE(chooseAnalysis(db).balanced);
  for (const auto& t : db.trials("S01")) ASSERT_EQ(t.status, session::TrialStatus::kCompleted) << t.id;
  const DesignAnalysis a = analyzeDesign(db);
  EXPECT_EQ(a.trials_excluded, 3);
  int spares = 0, excluded = 0;
  for (const DesignTrialScore& s : a.scores) {
    if (s.subject != "S01" || s.phase != "recall") continue;
    EXPECT_NE(s.trial, 2) << "the disturbed trial is analyzed";
    if (s.trial == 1) {
      EXPECT_EQ(s.trial_in_phase, 2) << "the spare takes the place of trial 2";
      ++spares;
    }
  }
  for (const DesignTrialScore& s : a.left_out) {
    if (s.subject == "S01" && s.phase == "recall" && s.trial == 2) {
      EXPECT_THAT(s.left_out, HasSubstr("exclude"));
      EXPECT_FALSE(s.disturbed.empty());
      ++excluded;
    }
  }
  EXPECT_EQ(spares, 3);
  EXPECT_EQ(excluded, 3);
}

TEST(DisturbedTrials, ExcludeWithoutASpareSaysWhatToDo) {
  HATTR_STARTS_NO_THREAD();
  CompletedStudy study(R"("disturbed_trials": "exclude", "analyzed_recall_trials": [1, 2, 3],)", stallInS01Recall2());
  const auto db = session::StudyDatabase::open(study.dir / "s.sqlite", session::OpenMode::kReadOnly);
  try {
    (void)analyzeStudy(db);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("subject S01 "));
    EXPECT_THAT(e.what(), HasSubstr(": 1 disturbed recall trial is excluded"));
    EXPECT_THAT(e.what(), HasSubstr("use \"repeat\" or \"flag\""));
  }
}

TEST(OneScorer, TheReportHattrDtwAndTheStudioAgreeOnEveryScore) {
  CompletedStudy study;
  const auto db = session::StudyDatabase::open(study.dir / "s.sqlite", session::OpenMode::kReadOnly);
  const StudyAnalysis a = analyzeStudy(db);
  const HapticProfile expert = db.expert("curve");
  const analysis::TrialScorer scorer(expert);
  for (const TrialCost& c : a.costs) {
    const analysis::TrialScore one = scorer.score(db.trialProfile(c.trial_id));
    for (const auto& [report, single] : {std::pair{c.score.x, one.x}, {c.score.y, one.y}, {c.score.z, one.z},
                                         {c.score.fx, one.fx}, {c.score.fy, one.fy}, {c.score.fz, one.fz}}) {
      EXPECT_NEAR(report, single, 1e-12 * std::max(1.0, std::abs(single)));
    }
  }
}

// What a power analysis does with its replicates: trials prepared as they end and scored in
// batches of any make-up give scoreAll's numbers to the bit; z is left out when asked.
TEST(OneScorer, TrialsPreparedOneByOneAndScoredInAnyBatchesGiveScoreAllsNumbers) {
  CompletedStudy study;
  const auto db = session::StudyDatabase::open(study.dir / "s.sqlite", session::OpenMode::kReadOnly);
  std::vector<HapticProfile> trials;
  for (const auto& t : db.trials()) trials.push_back(db.trialProfile(t.id));
  std::vector<const HapticProfile*> pointers;
  for (const auto& t : trials) pointers.push_back(&t);
  ASSERT_EQ(trials.size(), 3u * 3u * 4u);
  const analysis::TrialScorer scorer(db.expert("curve"));
  const std::vector<analysis::TrialScore> all = scorer.scoreAll(pointers, 2);

  const analysis::TrialScorer without_z(db.expert("curve"), {.score_z = false});
  std::vector<analysis::PreparedTrial> prepared;
  for (const auto& t : trials) prepared.push_back(without_z.prepare(t));
  // Batches of 1, 5 and the rest (a full SIMD block and a part of one, on any target).
  std::vector<analysis::TrialScore> batched;
  for (const auto& [first, count] : {std::pair<std::size_t, std::size_t>{0, 1}, {1, 5}, {6, prepared.size() - 6}}) {
    const auto scores = without_z.scorePrepared(std::span(prepared).subspan(first, count));
    batched.insert(batched.end(), scores.begin(), scores.end());
  }
  ASSERT_EQ(batched.size(), all.size());
  for (std::size_t i = 0; i < all.size(); ++i) {
    EXPECT_EQ(batched[i].x, all[i].x) << i;
    EXPECT_EQ(batched[i].y, all[i].y) << i;
    EXPECT_EQ(batched[i].fx, all[i].fx) << i;
    EXPECT_EQ(batched[i].fy, all[i].fy) << i;
    EXPECT_EQ(batched[i].fz, all[i].fz) << i;
    EXPECT_TRUE(std::isnan(batched[i].z)) << i;
    EXPECT_GT(all[i].z, 0.0) << i << ": scored when not asked otherwise";
  }
  // A plan of one outcome scores only its channels, the same bits for them.
  const analysis::TrialScorer shape_only(db.expert("curve"), {.score_z = false, .score_force = false});
  const analysis::TrialScorer force_only(db.expert("curve"), {.score_z = false, .score_shape = false});
  const std::vector<analysis::TrialScore> shapes = shape_only.scoreAll(pointers, 2);
  const std::vector<analysis::TrialScore> forces = force_only.scoreAll(pointers, 2);
  for (std::size_t i = 0; i < all.size(); ++i) {
    EXPECT_EQ(shapes[i].shape(), all[i].shape()) << i;
    EXPECT_TRUE(std::isnan(shapes[i].fx) && std::isnan(shapes[i].fy) && std::isnan(shapes[i].fz)) << i;
    EXPECT_EQ(forces[i].force(), all[i].force()) << i;
    EXPECT_TRUE(std::isnan(forces[i].x) && std::isnan(forces[i].y)) << i;
  }
}

// A scratch study (a power analysis's replicate) stores each trial's row but no samples; the run
// hands every trial as stored to the caller, who scores it; the analysis takes those scores and
// comes to the numbers of the same study stored in full. Its trials leave out the handwriting
// kinematics, which its analysis never reads.
TEST(ScratchStudy, KeepsNoSamplesAndItsAnalysisFromScoresGivenIsTheFullStudysToTheBit) {
  CompletedStudy full;
  std::map<std::int64_t, HapticProfile> handed;
  session::RunOptions options;
  options.stored = [&handed](const session::TrialRecord& t, const HapticProfile& p) {
    EXPECT_EQ(t.status, session::TrialStatus::kCompleted);
    EXPECT_TRUE(handed.emplace(t.id, p).second) << "trial " << t.id << " handed twice";
  };
  CompletedStudy scratch("", options, {.scratch = true});

  const auto full_db = session::StudyDatabase::open(full.dir / "s.sqlite", session::OpenMode::kReadOnly);
  const auto scratch_db = session::StudyDatabase::open(scratch.dir / "s.sqlite", session::OpenMode::kReadOnly);
  const std::vector<session::TrialRecord> trials = scratch_db.trials();
  ASSERT_EQ(handed.size(), trials.size());
  const std::string kinematics_key = session::kKinematicsPrefix + std::string("duration_s");
  for (const auto& t : trials) {
    EXPECT_EQ(t.status, session::TrialStatus::kCompleted);
    expectSameSamples(handed.at(t.id), full_db.trialProfile(t.id), fmt::format("trial {}", t.id));
    EXPECT_FALSE(handed.at(t.id).metadata().extra.contains(kinematics_key)) << "trial " << t.id;
    EXPECT_TRUE(full_db.trialProfile(t.id).metadata().extra.contains(kinematics_key)) << "trial " << t.id;
  }
  try {
    (void)scratch_db.trialProfile(trials.front().id);
    FAIL() << "a scratch study keeps no samples";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("has no recorded samples (it was run in a scratch study, which keeps none)"));
  }
  EXPECT_THROW((void)analyzeStudy(scratch_db), InputError) << "without the scores there is nothing to score";

  // The scores of the trials handed over, as a power analysis keeps them.
  const analysis::TrialScorer scorer(scratch_db.expert("curve"));
  std::map<std::int64_t, analysis::TrialScore> scores;
  for (const auto& [id, profile] : handed) scores[id] = scorer.score(profile);
  const StudyAnalysis from_scores = analyzeStudy(scratch_db, {.scored = &scores});
  const StudyAnalysis stored = analyzeStudy(full_db);
  ASSERT_EQ(from_scores.costs.size(), stored.costs.size());
  for (std::size_t i = 0; i < stored.costs.size(); ++i) {
    EXPECT_EQ(from_scores.costs[i].trajectory(), stored.costs[i].trajectory()) << i;
    EXPECT_EQ(from_scores.costs[i].forceProfile(), stored.costs[i].forceProfile()) << i;
  }
  EXPECT_EQ(from_scores.trajectory.overall.row("mode").p, stored.trajectory.overall.row("mode").p);
  EXPECT_EQ(from_scores.force.overall.row("mode").f, stored.force.overall.row("mode").f);
}

// The scores given are used as they are, the others computed: a given score shows in the costs.
TEST(StudyAnalysis, TakesTheScoresItIsGivenAndScoresTheOthers) {
  CompletedStudy study;
  const auto db = session::StudyDatabase::open(study.dir / "s.sqlite", session::OpenMode::kReadOnly);
  const StudyAnalysis plain = analyzeStudy(db);
  std::map<std::int64_t, analysis::TrialScore> given{{plain.costs[0].trial_id, {1.0, 2.0, 3.0, 4.0, 5.0, 6.0}}};
  const StudyAnalysis a = analyzeStudy(db, {.scored = &given});
  EXPECT_EQ(a.costs[0].trajectory(), 3.0);
  EXPECT_EQ(a.costs[0].forceProfile(), 15.0);
  for (std::size_t i = 1; i < a.costs.size(); ++i) EXPECT_EQ(a.costs[i].trajectory(), plain.costs[i].trajectory()) << i;
}

}  // namespace
}  // namespace hattr::report
