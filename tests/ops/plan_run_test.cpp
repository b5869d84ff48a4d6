// Planning a study (ops::runPlan over sim/plan.hpp's designs): the calibration design's answers
// against R's power.t.test and pwr.pwr.t.test, the state folder (a resume runs nothing again, a
// cut-off line is dropped, another plan or a bad line is refused), a simulated study's p-values
// as sim power's, its lab time, and the limits.

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "hattr/ops/plan_run.hpp"
#include "hattr/sim/plan.hpp"
#include "hattr/sim/power.hpp"
#include "support/test_support.hpp"
#include "support/thread_sanitizer.hpp"

namespace hattr::ops {
namespace {

using ::testing::HasSubstr;

/// R 4.2.2 (pwr 1.3.0): for two-sided t-tests at power 0.8,
///   power.t.test(delta = d, sd = 1, sig.level = a, power = 0.8, type = type)$n   (n_r),
///   pwr.t.test(d = d, sig.level = a, power = 0.8, type = type)$n                 (n_pwr),
/// and the power at ceiling(n_r), power.t.test(n = ceiling(n_r), ...)$power.
/// n is per group (two-sample) or pairs (paired).
struct RReference {
  bool paired;
  double d;
  double alpha;
  double n_r;
  int n;
  double n_pwr;
  double power_at_n;
};
constexpr RReference kR[] = {
    {false, 0.5, 0.05, 63.7658, 64, 63.7656, 0.8015}, {false, 0.8, 0.05, 25.5246, 26, 25.5246, 0.8075},
    {false, 1.2, 0.05, 11.9423, 12, 11.9423, 0.8021}, {false, 0.5, 0.01, 95.1036, 96, 95.1036, 0.8045},
    {false, 0.8, 0.01, 38.1883, 39, 38.1883, 0.8104}, {false, 1.2, 0.01, 17.9495, 18, 17.9495, 0.8015},
    {true, 0.5, 0.05, 33.3672, 34, 33.3671, 0.8078},  {true, 0.8, 0.05, 14.3028, 15, 14.3028, 0.8213},
    {true, 1.2, 0.05, 7.5877, 8, 7.5877, 0.8279},     {true, 0.5, 0.01, 50.0647, 51, 50.0647, 0.8094},
    {true, 0.8, 0.01, 21.6310, 22, 21.6310, 0.8095},  {true, 1.2, 0.01, 11.5245, 12, 11.5244, 0.8260},
};

std::vector<PlanSearchSpec> calibration(bool paired, double d, std::uint64_t seed = 1) {
  std::vector<PlanSearchSpec> searches;
  searches.push_back({sim::makeCalibrationDesign({.paired = paired, .effect_size = d, .seed = seed}), ""});
  return searches;
}

PlanRunOptions calibrationRun(double alpha) {
  PlanRunOptions o;
  o.search = {.min_subjects = 3, .max_subjects = 200, .batch = 500, .max_replicates = 10'000};
  o.alpha = alpha;
  return o;
}

TEST(PlanCalibration, TheSubjectCountsAreRsPowerTTestsWithinTheStatedMonteCarloRange) {
  int checked = 0;
  for (const RReference& r : kR) {
    // Sanitized builds check one two-sample and one paired case (the same code, slower).
    if (test::kSanitized && !(r.d == 0.8 && r.alpha == 0.05)) continue;
    ++checked;
    std::vector<PlanSearchSpec> searches = calibration(r.paired, r.d);
    const report::PlanSearchResult result = runPlan(searches, calibrationRun(r.alpha)).report.searches.at(0).result;
    SCOPED_TRACE(testing::Message() << (r.paired ? "paired" : "two-sample") << " d " << r.d << " alpha " << r.alpha);
    ASSERT_TRUE(result.answer);
    // R's n lies in the range the plan states, and the range is narrow (a few subjects).
    EXPECT_LE(result.range_low, r.n);
    EXPECT_GE(result.range_high, r.n);
    EXPECT_LE(result.range_high - result.range_low, std::max(4, r.n / 6));
    EXPECT_NEAR(r.n_pwr, r.n_r, 1e-3);  // pwr agrees with power.t.test
    // Where the plan ran R's n, R's power lies in that design's 99.9 % interval.
    for (const auto& p : result.points) {
      if (p.subjects != r.n) continue;
      const analysis::Proportion wide = analysis::clopperPearson(p.power.successes, p.power.trials, 0.999);
      EXPECT_LE(wide.lower, r.power_at_n);
      EXPECT_GE(wide.upper, r.power_at_n);
    }
  }
  EXPECT_EQ(checked, test::kSanitized ? 2 : 12);
}

TEST(PlanCalibration, AnotherEffectSizeIsNotInTheRange) {
  // The check can fail: d = 0.5's design, asked of R's d = 0.6 answer (45 per group), is refused.
  std::vector<PlanSearchSpec> searches = calibration(false, 0.5);
  const report::PlanSearchResult result = runPlan(searches, calibrationRun(0.05)).report.searches.at(0).result;
  EXPECT_GT(result.range_low, 45);
}

TEST(PlanState, AResumeRunsNothingAgainAndACutOffLineIsDropped) {
  test::TempDir dir;
  PlanRunOptions o = calibrationRun(0.05);
  o.search.batch = 100;
  o.search.max_replicates = 2000;
  o.state = dir / "state";
  std::vector<PlanSearchSpec> searches = calibration(true, 0.8);
  const PlanRunResult first = runPlan(searches, o);
  EXPECT_GT(first.replicates_run, 0);
  const std::filesystem::path lines = o.state / "outcomes-main.jsonl";
  ASSERT_TRUE(std::filesystem::exists(lines));
  ASSERT_TRUE(std::filesystem::exists(o.state / "plan.json"));

  // Again: every outcome is read, none run.
  const PlanRunResult again = runPlan(searches, o);
  EXPECT_EQ(again.replicates_run, 0);
  EXPECT_EQ(report::planReportToJson(again.report), report::planReportToJson(first.report));

  // A kill while a line was written: the line is dropped and its replicate run again.
  const std::string text = test::readText(lines);
  const std::size_t last = text.rfind('\n', text.size() - 2);
  std::filesystem::resize_file(lines, last + 1 + 10);  // the last line cut to 10 characters
  const PlanRunResult resumed = runPlan(searches, o);
  EXPECT_EQ(resumed.replicates_run, 1);
  EXPECT_EQ(report::planReportToJson(resumed.report), report::planReportToJson(first.report));
  EXPECT_EQ(test::readText(lines), text);  // the same lines, whole again

  // Another plan in the same folder is refused, naming what differs.
  PlanRunOptions other = o;
  other.alpha = 0.01;
  try {
    (void)runPlan(searches, other);
    ADD_FAILURE() << "another plan was accepted";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("plan.json: the folder holds another plan (its \"alpha\" differs)"));
  }
  // A line that is not an outcome is refused, naming the file and line.
  { std::ofstream(lines, std::ios::app) << "{\"search\": 0, \"subjects\": \"many\"}\n"; }
  try {
    (void)runPlan(searches, o);
    ADD_FAILURE() << "a bad line was accepted";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr(lines.string() + ":"));
  }
}

TEST(PlanState, AWriterAtWorkLocksOthersOutAndAnImpossibleLineIsNamed) {
  test::TempDir dir;
  PlanRunOptions o = calibrationRun(0.05);
  o.search.batch = 100;
  o.search.max_replicates = 1000;
  o.state = dir / "state";
  std::vector<PlanSearchSpec> searches = calibration(true, 1.2);
  (void)runPlan(searches, o);
  const std::filesystem::path lines = o.state / "outcomes-main.jsonl";
  {
    // Another process of the same writer name at work (its lock, held here) is refused.
    const int fd = ::open(lines.c_str(), O_RDONLY | O_CLOEXEC);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(::flock(fd, LOCK_EX), 0);
    try {
      (void)runPlan(searches, o);
      ADD_FAILURE() << "a second writer was let in";
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr(lines.string() + ": another `hattr sim plan` is writing this file now"));
    }
    ::close(fd);
  }
  EXPECT_EQ(runPlan(searches, o).replicates_run, 0) << "the lock is gone with its holder";
  // A replicate no plan runs is refused with its file and line.
  const std::string before = test::readText(lines);
  const auto count = std::count(before.begin(), before.end(), '\n');
  { std::ofstream(lines, std::ios::app) << "{\"search\": 0, \"subjects\": 8, \"replicate\": -1, \"p\": 0.5}\n"; }
  try {
    (void)runPlan(searches, o);
    ADD_FAILURE() << "a negative replicate was accepted";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr(fmt::format("{}:{}: expected a search and a replicate of 0 or more", lines.string(),
                                                count + 1)));
    EXPECT_THAT(e.what(), HasSubstr("replicate -1"));
  }
}

// Under MPI only rank 0 opens the state folder; another rank gets what it read through the
// exchange, so a resumed plan runs nothing there either, and the folder need not be on its node.
TEST(PlanState, AnMpiRankButTheFirstGetsTheStateThroughTheExchangeAndNeverOpensTheFolder) {
  test::TempDir dir;
  PlanRunOptions o = calibrationRun(0.05);
  o.search.batch = 100;
  o.search.max_replicates = 1000;
  o.state = dir / "state";
  std::vector<PlanSearchSpec> searches = calibration(true, 1.2);
  const PlanRunResult first = runPlan(searches, o);
  // Rank 0's contribution to the first exchange: the lines it read.
  std::vector<double> rank0;
  std::ifstream in(o.state / "outcomes-main.jsonl");
  for (std::string line; std::getline(in, line);) {
    const auto j = nlohmann::json::parse(line);
    rank0.insert(rank0.end(), {j["search"].get<double>(), j["subjects"].get<double>(), j["replicate"].get<double>(),
                               j["p"].get<double>()});
  }
  ASSERT_FALSE(rank0.empty());
  PlanRunOptions rank1 = o;
  rank1.state = dir / "not-on-this-node";
  rank1.writes_state = false;
  rank1.part = 1;
  rank1.parts = 2;
  int exchanges = 0;
  rank1.exchange = [&](const std::vector<double>& mine) {
    ++exchanges;
    EXPECT_TRUE(mine.empty()) << "rank 1 has read nothing to send";
    return rank0;
  };
  const PlanRunResult second = runPlan(searches, rank1);
  EXPECT_EQ(exchanges, 1);
  EXPECT_EQ(second.replicates_run, 0);
  EXPECT_EQ(report::planReportToJson(second.report), report::planReportToJson(first.report));
  EXPECT_FALSE(std::filesystem::exists(rank1.state));
}

TEST(PlanLimits, LimitsThatNoDesignMeetsAreRefused) {
  std::vector<PlanSearchSpec> searches = calibration(false, 0.8);
  PlanRunOptions o = calibrationRun(0.05);
  o.search.min_subjects = 50;
  o.search.max_subjects = 40;
  EXPECT_THROW((void)runPlan(searches, o), InputError);
  o = calibrationRun(0.05);
  o.parts = 2;  // shards without a state folder to share
  EXPECT_THROW((void)runPlan(searches, o), InputError);
}

/// The paper's study, small: 2 + 2 trials per mode, the sanitizers' short glyph.
sim::StudyPlanOptions smallStudy(int trials, const std::string& comparison = "mode") {
  sim::StudyPlanOptions o;
  o.power.glyph = test::kStudyGlyph;
  o.power.training_trials = trials;
  o.power.recall_trials = trials;
  o.power.seed = 5;
  o.max_subjects = 4;
  o.max_replicates = 4;
  o.comparison = comparison;
  return o;
}

TEST(PlanStudy, ADesignsPValuesAreSimPowersAndItsLabTimeIsItsTrials) {
  HATTR_SKIP_UNDER_THREAD_SANITIZER("two simulated replicates of the paper's study; PowerStudy's tests run them there");
  const auto design = sim::makeStudyPlanDesign(smallStudy(2));
  const std::vector<int> replicates{0, 1};
  // The same replicates as `hattr sim power --subjects 3,4`: its 3-subject design's mode effect,
  // on shape and on force (a plan scores only its outcome's channels: the same bits).
  sim::PowerOptions power = smallStudy(2).power;
  power.subject_counts = {3, 4};
  power.replicates = 4;
  const sim::PowerStudy study(power);
  const std::vector<report::ReplicateOutcome> outcomes = study.runReplicates(replicates);
  for (const std::string outcome : {"shape", "force"}) {
    sim::StudyPlanOptions o = smallStudy(2);
    o.outcome = outcome;
    const std::vector<double> p = sim::makeStudyPlanDesign(o)->pValues(3, replicates, {});
    ASSERT_EQ(p.size(), 2u);
    for (std::size_t k = 0; k < 2; ++k) {
      const double expected = outcomes[k].designs.at(0)[outcome == "shape" ? 0 : 1].p_mode;
      EXPECT_TRUE(p[k] == expected || (std::isnan(p[k]) && std::isnan(expected)))
          << outcome << " " << k << ": " << p[k] << " " << expected;
    }
  }
  // Lab time: 3 modes × (t + t) trials × (the expert's duration + 10 s rest) + 10 min setup, so
  // its trials' part doubles with twice the trials.
  const double two = design->labSecondsPerSubject() - 600.0;
  const double four = sim::makeStudyPlanDesign(smallStudy(4))->labSecondsPerSubject() - 600.0;
  EXPECT_GT(two, 12 * 10.0);
  EXPECT_NEAR(four, 2.0 * two, 1e-9);
  EXPECT_EQ(design->groups(), 1);
}

// A plan by the mixed model, or of a kinematic outcome: its p is that of the same replicate's
// analyzed trials (kept by a power analysis that scores every channel, while the plan scores
// only its outcome's: shape alone, or none for a kinematic measure).
TEST(PlanStudy, AMixedOrKinematicPlansPValuesAreThoseOfItsReplicatesTrials) {
  HATTR_SKIP_UNDER_THREAD_SANITIZER("simulated replicates of the paper's study; PowerStudy's tests run them there");
  const std::vector<int> replicates{0, 1};
  sim::PowerOptions power = smallStudy(2).power;
  power.subject_counts = {4};
  power.replicates = 4;
  power.keep_trials = true;
  power.kinematic = "mean_speed_m_per_s";
  const std::vector<report::ReplicateOutcome> outcomes = sim::PowerStudy(power).runDesign(replicates, 3);
  struct Case {
    sim::PlanAnalysis analysis;
    std::string outcome;
    std::string comparison;
  };
  int finite = 0;
  // Pairs in the study's order (BASIC, PCONTROL, ALPHA), as the plan names them: the model's
  // reference is the pair's first (the other order gives the same p up to rounding, ~1e-12).
  for (const Case& c : {Case{sim::PlanAnalysis::kMixed, "shape", "PCONTROL-ALPHA"},
                        Case{sim::PlanAnalysis::kAnova, "mean_speed_m_per_s", "mode"},
                        Case{sim::PlanAnalysis::kMixed, "mean_speed_m_per_s", "BASIC-PCONTROL"}}) {
    sim::StudyPlanOptions o = smallStudy(2, c.comparison);
    o.analysis = c.analysis;
    o.outcome = c.outcome;
    const std::vector<double> p = sim::makeStudyPlanDesign(o)->pValues(3, replicates, {});
    const auto dash = c.comparison.find('-');
    const sim::TrialsComparison how{.analysis = c.analysis, .outcome = c.outcome,
                                    .pair_a = dash == std::string::npos ? "" : c.comparison.substr(0, dash),
                                    .pair_b = dash == std::string::npos ? "" : c.comparison.substr(dash + 1)};
    ASSERT_EQ(p.size(), 2u);
    for (std::size_t k = 0; k < 2; ++k) {
      ASSERT_EQ(outcomes[k].trials.size(), 3u * 3u * 1u) << "3 subjects, 3 modes, 1 analyzed recall trial";
      const double expected = sim::comparisonP(outcomes[k].trials, how);
      EXPECT_TRUE(p[k] == expected || (std::isnan(p[k]) && std::isnan(expected)))
          << c.outcome << " " << c.comparison << " " << k << ": " << p[k] << " " << expected;
      if (std::isfinite(p[k])) ++finite;
    }
  }
  EXPECT_GE(finite, 4) << "most of these analyses give a p";
}

TEST(PlanStudy, AComparisonOfAStrategyTheDesignDoesNotHaveIsRefused) {
  try {
    (void)sim::makeStudyPlanDesign(smallStudy(2, "ALPHA-MIRROR"));
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("--compare ALPHA-MIRROR: expected \"mode\" or two of the design's BASIC, "
                                    "PCONTROL, ALPHA joined by '-'"));
  }
  EXPECT_NO_THROW((void)sim::makeStudyPlanDesign(smallStudy(2, "PCONTROL-ALPHA")));  // either order
}

}  // namespace
}  // namespace hattr::ops
