#include "hattr/sim/power.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <random>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/analysis/proportion.hpp"
#include "hattr/core/error.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/analysis/anova.hpp"
#include "hattr/report/design_analysis.hpp"
#include "hattr/session/study_runner.hpp"
#include "hattr/sim/in_silico.hpp"
#include "hattr/sim/participant.hpp"
#include "support/test_support.hpp"
#include "support/thread_sanitizer.hpp"

namespace hattr::sim {
namespace {

using ::testing::HasSubstr;

/// Equal to the bit, or both NaN (no value in either analysis).
void expectSame(double a, double b, const std::string& what) {
  if (std::isnan(a) || std::isnan(b)) {
    EXPECT_TRUE(std::isnan(a) && std::isnan(b)) << what << ": " << a << " vs " << b;
  } else {
    EXPECT_EQ(a, b) << what;
  }
}

/// The outcome the power analysis reads from an analysis, checked against its own reading.
void expectOutcomeOf(const report::MetricOutcome& got, const report::MetricResult& metric, const report::PowerPlan& plan,
                     const std::string& what) {
  expectSame(got.p_mode, metric.overall.row("mode").p, what + " p");
  expectSame(got.partial_eta_sq, metric.overall.row("mode").partial_eta_sq, what + " eta");
  ASSERT_TRUE(metric.tukey.has_value()) << what;
  ASSERT_EQ(got.p_pairs.size(), plan.pairs().size());
  // Each plan pair ("BASIC-PCONTROL") is found in Tukey's comparisons, either way round.
  const std::vector<std::string> pairs = plan.pairs();
  for (std::size_t k = 0; k < got.p_pairs.size(); ++k) {
    const std::string& pair = pairs[k];
    int matches = 0;
    for (const auto& c : metric.tukey->comparisons) {
      if (pair == c.level + "-" + c.other_level || pair == c.other_level + "-" + c.level) {
        expectSame(got.p_pairs[k], c.p_adjusted, what + " " + pair);
        ++matches;
      }
    }
    EXPECT_EQ(matches, 1) << what << " " << pair;
  }
}

/// A design's study file made, run with simulated subjects and analyzed, as a study of its own.
report::DesignAnalysis runAndAnalyze(const std::filesystem::path& study_file, const std::filesystem::path& db_file) {
  { (void)session::StudyDatabase::create(db_file, session::loadStudy(study_file)); }
  session::StudyDatabase db = session::StudyDatabase::open(db_file, session::OpenMode::kRunner);
  (void)session::StudyRunner(db, [](const session::SubjectRecord& s, const HapticProfile& e) {
    return makeSimulatedParticipant(s, e);
  }).run({});
  return report::analyzeDesign(db);
}

// Replicate r is the in-silico study with seed + r, and a design of N subjects analyzes its
// first N: the same numbers as studies of 3 and of 4 subjects run on their own.
TEST(PowerStudy, AReplicateIsTheInSilicoStudyWithSeedPlusRAndEachDesignItsFirstSubjects) {
  HATTR_SKIP_UNDER_THREAD_SANITIZER("a replicate compared with two in silico studies; subjects at once run under it in "
                                    "InSilicoStudy.SubjectsRunAtOnceGiveTheSameTrialsToTheBitAsOneAtATime");
  test::TempDir dir;
  const PowerStudy power({.glyph = test::kStudyGlyph, .training_trials = 1, .recall_trials = 3,
                          .subject_counts = {4, 3}, .replicates = 2, .seed = 5, .threads = 2, .scratch = dir / "scratch"});
  EXPECT_EQ(power.plan().subject_counts, (std::vector<int>{3, 4}));
  EXPECT_EQ(power.plan().pairs(), (std::vector<std::string>{"BASIC-PCONTROL", "BASIC-ALPHA", "PCONTROL-ALPHA"}));
  const report::ReplicateOutcome outcome = power.runReplicate(1);
  EXPECT_EQ(outcome.replicate, 1);
  ASSERT_EQ(outcome.designs.size(), 2u);
  EXPECT_FALSE(std::filesystem::exists(dir / "scratch" / "replicate-1")) << "a replicate's database is removed";

  for (const int n : {3, 4}) {
    const InSilicoResult alone =
        runInSilicoStudy({.out_dir = dir / std::to_string(n), .glyph = test::kStudyGlyph, .subjects = n, .seed = 6,
                          .training_trials = 1, .recall_trials = 3, .write_report = false});
    const auto& design = outcome.designs[n == 3 ? 0 : 1];
    expectOutcomeOf(design[0], alone.analysis.trajectory, power.plan(), fmt::format("{} subjects trajectory", n));
    expectOutcomeOf(design[1], alone.analysis.force, power.plan(), fmt::format("{} subjects force", n));
  }
  // The two designs are different analyses (4 subjects are not 3).
  EXPECT_NE(outcome.designs[0][0].p_mode, outcome.designs[1][0].p_mode);
}

TEST(PowerStudy, UnderAHypothesisAReplicateIsTheInSilicoStudyUnderIt) {
  HATTR_SKIP_UNDER_THREAD_SANITIZER("a replicate compared with two in silico studies; subjects at once run under it in "
                                    "InSilicoStudy.SubjectsRunAtOnceGiveTheSameTrialsToTheBitAsOneAtATime");
  HATTR_SKIP_UNDER_ADDRESS_SANITIZER("48 s under it; a replicate's path runs there in "
                                     "PowerStudy.AReplicateIsTheInSilicoStudy..., the hypotheses' models in "
                                     "HypothesesCli.TabulatesThePapersPoints...");
  test::TempDir dir;
  const PowerStudy power({.training_trials = 2, .recall_trials = 3, .subject_counts = {3}, .replicates = 1, .seed = 8,
                          .threads = 2, .hypothesis = "guidance-dependent", .scratch = dir / "scratch"});
  EXPECT_EQ(power.plan().study.at("trainee"), "guidance-dependent") << "replicates of another model do not merge";
  const report::ReplicateOutcome outcome = power.runReplicate(0);
  const auto inSilico = [&](std::optional<LearningHypothesis> h, const char* name) {
    return runInSilicoStudy({.out_dir = dir / name, .subjects = 3, .seed = 8, .training_trials = 2,
                             .recall_trials = 3, .hypothesis = h, .write_report = false});
  };
  const InSilicoResult dependent = inSilico(LearningHypothesis::kGuidanceDependent, "dependent");
  expectOutcomeOf(outcome.designs[0][0], dependent.analysis.trajectory, power.plan(), "trajectory");
  expectOutcomeOf(outcome.designs[0][1], dependent.analysis.force, power.plan(), "force");
  // And it is not the position-plan learner's study: guided, this learner learns less.
  const InSilicoResult plain = inSilico(std::nullopt, "plain");
  EXPECT_NE(outcome.designs[0][0].p_mode, plain.analysis.trajectory.overall.row("mode").p);
}

// A design of groups: replicate r is the design with N simulated subjects per group, seeded as
// the in-silico study with seed + r, its groups compared at retention by a one-way ANOVA of
// each subject's mean cost and Tukey HSD; a design of N analyzes each group's first N.
TEST(PowerStudy, AGroupDesignsReplicateIsTheDesignRunWithItsSubjectsAndCompared) {
  HATTR_SKIP_UNDER_THREAD_SANITIZER("a replicate compared with the same study run on its own");
  test::TempDir dir;
  const InSilicoResult expert = runInSilicoStudy({.out_dir = dir / "expert", .glyph = test::kStudyGlyph, .subjects = 2,
                                                  .seed = 1, .training_trials = 0, .recall_trials = 2, .write_report = false});
  const std::string groups = R"({"name": "g", "skill": "na", "experts": {"na": "EXPERT"},
    "protocol": {"rest_s": 0}, "order": {"kind": "fixed"}, "world": {"relief": {"kind": "flat"}},
    "groups": [{"name": "one", "strategies": ["basic"], "subjects": SUBJECTS_ONE},
               {"name": "two", "strategies": ["alpha"], "subjects": SUBJECTS_TWO}],
    "sessions": [{"day": 0, "blocks": [{"phase": "training", "strategy": "group", "trials": 2},
                                       {"phase": "post-test", "trials": 1}]},
                 {"day": 1, "blocks": [{"phase": "retention", "trials": 2}]}]})";
  const auto write = [&](const std::filesystem::path& file, const std::string& one, const std::string& two) {
    std::string text = groups;
    text.replace(text.find("EXPERT"), 6, (dir / "expert" / "expert.csv").string());
    text.replace(text.find("SUBJECTS_ONE"), 12, one);
    text.replace(text.find("SUBJECTS_TWO"), 12, two);
    test::writeText(file, text);
  };
  write(dir / "design.json", R"({"count": 3})", R"({"count": 3})");
  const PowerStudy power({.study = dir / "design.json", .subject_counts = {4, 3}, .replicates = 2, .seed = 5,
                          .threads = 1, .scratch = dir / "scratch"});
  EXPECT_EQ(power.plan().modes, (std::vector<std::string>{"one", "two"}));
  EXPECT_EQ(power.plan().study.at("tested_phase"), "retention");
  const report::ReplicateOutcome outcome = power.runReplicate(1);
  ASSERT_EQ(outcome.designs.size(), 2u);

  // The same replicate as a study of its own: subjects one01..04 and two01..04, seeds 6·1000 + place.
  const auto subjects = [](const std::string& group, int first_place) {
    std::string list = "[";
    for (int i = 1; i <= 4; ++i) {
      list += fmt::format(R"({}{{"id": "{}{:02}", "seed": {}}})", i == 1 ? "" : ", ", group, i, 6000 + first_place + i - 1);
    }
    return list + "]";
  };
  write(dir / "alone.json", subjects("one", 1), subjects("two", 5));
  const report::DesignAnalysis alone = runAndAnalyze(dir / "alone.json", dir / "alone.sqlite");
  for (const int n : {3, 4}) {
    analysis::OneWayData data;
    for (const std::string group : {"one", "two"}) {
      for (int i = 1; i <= n; ++i) {
        const std::string id = fmt::format("{}{:02}", group, i);
        double sum = 0.0;
        int count = 0;
        for (const auto& t : alone.scores) {
          if (t.subject == id && t.phase == "retention") {
            sum += t.shape();
            ++count;
          }
        }
        data.group.push_back(group);
        data.y.push_back(sum / count);
      }
    }
    const double p = analysis::oneWayAnova(data).row("group").p;
    EXPECT_EQ(outcome.designs[n == 3 ? 0 : 1][0].p_mode, p) << n << " per group";
    EXPECT_EQ(outcome.designs[n == 3 ? 0 : 1][0].p_pairs.front(), analysis::tukeyHsdOneWay(data).comparisons.front().p_adjusted);
  }
  EXPECT_NE(outcome.designs[0][0].p_mode, outcome.designs[1][0].p_mode);
}

// A hundred subjects per group: the largest design's subjects one100 and two100 are the 100th of
// their groups, not the 0th (an id's number is all its digits after the group's name), so the
// 3-per-group design is its groups' first three, seeded by their place in the largest design.
TEST(PowerStudy, AGroupOfAHundredNumbersItsSubjectsPastNinetyNine) {
  HATTR_SKIP_UNDER_THREAD_SANITIZER("200 simulated subjects");
  HATTR_SKIP_UNDER_ADDRESS_SANITIZER("200 simulated subjects; the numbering is the same code at 4 per group in "
                                     "PowerStudy.AGroupDesignsReplicateIsTheDesignRunWithItsSubjectsAndCompared");
  test::TempDir dir;
  const InSilicoResult expert = runInSilicoStudy({.out_dir = dir / "expert", .glyph = test::kStudyGlyph, .subjects = 2,
                                                  .seed = 1, .training_trials = 0, .recall_trials = 2, .write_report = false});
  const auto write = [&](const std::filesystem::path& file, const std::string& one, const std::string& two) {
    test::writeText(file, fmt::format(R"({{"name": "h", "skill": "na", "experts": {{"na": "{}"}},
      "protocol": {{"rest_s": 0}}, "order": {{"kind": "fixed"}}, "world": {{"relief": {{"kind": "flat"}}}},
      "groups": [{{"name": "one", "strategies": ["basic"], "subjects": {}}},
                 {{"name": "two", "strategies": ["alpha"], "subjects": {}}}],
      "sessions": [{{"day": 0, "blocks": [{{"phase": "training", "strategy": "group", "trials": 1}},
                                         {{"phase": "retention", "trials": 1}}]}}]}})",
                                      (dir / "expert" / "expert.csv").string(), one, two));
  };
  write(dir / "design.json", R"({"count": 3})", R"({"count": 3})");
  const PowerStudy power({.study = dir / "design.json", .subject_counts = {3, 100}, .replicates = 1, .seed = 5,
                          .threads = 2, .scratch = dir / "scratch"});
  const report::ReplicateOutcome outcome = power.runReplicate(0);
  ASSERT_EQ(outcome.designs.size(), 2u);
  // The 3-per-group design as a study of its own: one01..03 and two01..03, seeds 5·1000 + place.
  const auto three = [](const std::string& group, int first_place) {
    return fmt::format(R"([{{"id": "{0}01", "seed": {1}}}, {{"id": "{0}02", "seed": {2}}}, {{"id": "{0}03", "seed": {3}}}])",
                       group, 5000 + first_place, 5001 + first_place, 5002 + first_place);
  };
  write(dir / "alone.json", three("one", 1), three("two", 101));
  const report::DesignAnalysis alone = runAndAnalyze(dir / "alone.json", dir / "alone.sqlite");
  std::vector<const report::DesignTrialScore*> retention;
  for (const auto& t : alone.scores) {
    if (t.phase == "retention") retention.push_back(&t);
  }
  ASSERT_EQ(retention.size(), 6u);
  for (const bool shape : {true, false}) {
    analysis::OneWayData data = report::groupSubjectMeans(retention, shape);
    data.factor = "group";
    expectSame(outcome.designs[0][shape ? 0 : 1].p_mode, analysis::oneWayAnova(data).row("group").p,
               shape ? "shape" : "force");
  }
  EXPECT_NE(outcome.designs[0][0].p_mode, outcome.designs[1][0].p_mode);
}

// A design comparing strategies within subjects over two sessions a week apart (week-apart,
// made small): replicate r is that design with its subjects (all01 ...) seeded as the in-silico
// study with seed + r, and each strategy's recall trials, numbered through both sessions, go into
// the paper's mode × subject analysis.
TEST(PowerStudy, AWeekApartReplicateIsTheDesignRunWithItsSubjectsAndItsStrategiesCompared) {
  HATTR_SKIP_UNDER_THREAD_SANITIZER("a replicate compared with the same study run on its own");
  test::TempDir dir;
  const InSilicoResult expert = runInSilicoStudy({.out_dir = dir / "expert", .glyph = test::kStudyGlyph, .subjects = 2,
                                                  .seed = 1, .training_trials = 0, .recall_trials = 2, .write_report = false});
  std::string blocks;
  for (int k = 1; k <= 3; ++k) {
    blocks += fmt::format(R"({}{{"phase": "training", "strategy": {{"order": {}}}, "trials": 1}},
                             {{"phase": "recall", "strategy": {{"order": {}}}, "guidance": false, "trials": 2}})",
                          k == 1 ? "" : ", ", k, k);
  }
  const auto write = [&](const std::filesystem::path& file, const std::string& subjects) {
    test::writeText(file, fmt::format(R"({{"name": "w", "skill": "na", "experts": {{"na": "{}"}},
      "protocol": {{"rest_s": 0}}, "order": {{"kind": "latin-square"}}, "world": {{"relief": {{"kind": "flat"}}}},
      "groups": [{{"name": "all", "strategies": ["basic", "pcontrol", "alpha"], "subjects": {}}}],
      "sessions": [{{"day": 0, "blocks": [{}]}}, {{"day": 7, "blocks": [{}]}}]}})",
                                      (dir / "expert" / "expert.csv").string(), subjects, blocks, blocks));
  };
  write(dir / "design.json", R"({"count": 3})");
  const PowerStudy power({.study = dir / "design.json", .subject_counts = {3}, .replicates = 2, .seed = 5,
                          .threads = 1, .scratch = dir / "scratch"});
  EXPECT_EQ(power.plan().modes, (std::vector<std::string>{"BASIC", "PCONTROL", "ALPHA"}));
  EXPECT_EQ(power.plan().study.at("tested_phase"), "recall");
  const report::ReplicateOutcome outcome = power.runReplicate(1);

  // The same replicate as a study of its own: subjects all01..03, seeds 6·1000 + place.
  write(dir / "alone.json", R"([{"id": "all01", "seed": 6001}, {"id": "all02", "seed": 6002}, {"id": "all03", "seed": 6003}])");
  const report::DesignAnalysis alone = runAndAnalyze(dir / "alone.json", dir / "alone.sqlite");
  std::vector<report::TrialCost> costs;
  for (const auto& t : alone.scores) {
    if (t.phase == "recall") costs.push_back({t.trial_id, t.subject, t.strategy, t.trial_in_phase, t.score, ""});
  }
  ASSERT_EQ(costs.size(), 3u * 3u * 4u) << "2 recall trials per strategy in each of 2 sessions";
  EXPECT_EQ(std::count_if(costs.begin(), costs.end(), [](const report::TrialCost& c) { return c.trial == 4; }), 9)
      << "numbered through both sessions";
  expectOutcomeOf(outcome.designs[0][0], report::analyzeMetric("trajectory", costs, true), power.plan(), "trajectory");
  expectOutcomeOf(outcome.designs[0][1], report::analyzeMetric("force", costs, false), power.plan(), "force");
}

// Replicates two at once (each on its own thread, its subjects in turn, each thread keeping
// its paper), or one at a time with its subjects at once: the outcomes of each on its own.
TEST(PowerStudy, ReplicatesRunTogetherAreEachTheSameAsRunOnItsOwn) {
  HATTR_SKIP_UNDER_THREAD_SANITIZER("five replicates took 231 s under it; "
                                    "PowerStudy.TwoReplicatesOnTwoThreadsShareNothingWritable runs the threads there");
  HATTR_SKIP_UNDER_ADDRESS_SANITIZER("67 s under it; PowerStudy.TwoReplicatesOnTwoThreadsShareNothingWritable runs "
                                     "replicates two at once there");
  test::TempDir dir;
  const PowerStudy power({.training_trials = 0, .recall_trials = 3, .subject_counts = {3}, .replicates = 2,
                          .seed = 11, .threads = 2, .scratch = dir / "scratch"});
  // The outcome's numbers as bits (a NaN equals itself).
  const auto encoded = [](const report::ReplicateOutcome& o) {
    std::vector<double> flat;
    report::encodeOutcome(o, flat);
    std::vector<std::uint64_t> bits;
    for (const double v : flat) bits.push_back(std::bit_cast<std::uint64_t>(v));
    return bits;
  };
  const std::vector<int> order{1, 0};
  double last_progress = 0.0;
  const std::vector<report::ReplicateOutcome> together = power.runReplicates(order, [&](double done) {
    EXPECT_GE(done, 0.0);
    EXPECT_LE(done, 2.0 + 1e-9);
    last_progress = done;
  });
  EXPECT_NEAR(last_progress, 2.0, 1e-9);
  const std::vector<report::ReplicateOutcome> one_at_a_time = power.runReplicates(std::vector<int>{1});
  EXPECT_THROW((void)power.runReplicates(std::vector<int>{0, 0}), InputError) << "a replicate given twice";
  ASSERT_EQ(together.size(), 2u);
  ASSERT_EQ(one_at_a_time.size(), 1u);
  for (std::size_t k = 0; k < order.size(); ++k) {
    EXPECT_EQ(together[k].replicate, order[k]);
    const auto alone = encoded(power.runReplicate(order[k]));
    EXPECT_EQ(encoded(together[k]), alone) << "replicate " << order[k];
    if (order[k] == 1) {
      EXPECT_EQ(encoded(one_at_a_time.front()), alone);
    }
  }
  EXPECT_NE(encoded(together[0]), encoded(together[1])) << "different replicates are different studies";
}

// The replicates' threads for ThreadSanitizer, as small as a replicate gets: two at once, each
// with its outcome (found a race on glibc's signgam in std::lgamma, clean-clone run 26).
TEST(PowerStudy, TwoReplicatesOnTwoThreadsShareNothingWritable) {
  test::TempDir dir;
  const PowerStudy power({.glyph = test::kStudyGlyph, .training_trials = 0, .recall_trials = 2, .subject_counts = {3},
                          .replicates = 2, .seed = 3, .threads = 2, .scratch = dir / "scratch"});
  const std::vector<report::ReplicateOutcome> outcomes = power.runReplicates(std::vector<int>{0, 1});
  ASSERT_EQ(outcomes.size(), 2u);
  EXPECT_EQ(outcomes[0].replicate, 0);
  EXPECT_EQ(outcomes[1].replicate, 1);
  EXPECT_EQ(outcomes[0].designs.size(), 1u);
}

TEST(PowerStudy, RefusesDesignsItCannotAnalyzeNamingTheOption) {
  HATTR_STARTS_NO_THREAD();
  const auto message = [](const PowerOptions& o) {
    try {
      const PowerStudy power(o);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_THAT(message({.subject_counts = {2, 10}}), HasSubstr("subjects: expected 3 to 1000 subjects per design"));
  EXPECT_THAT(message({.subject_counts = {6, 6}}), HasSubstr("subjects: 6 is given twice"));
  EXPECT_THAT(message({.replicates = 0}), HasSubstr("replicates: expected 1 to 1000000, got 0"));
  EXPECT_THAT(message({.alpha = 1.0}), HasSubstr("alpha: expected a level in (0, 1), got 1"));
  EXPECT_THAT(message({.recall_trials = 1}), HasSubstr("trials: expected >= 2 recall"));
  EXPECT_THAT(message({.hypothesis = "telepathy"}),
              HasSubstr("hypothesis: expected one of position-plan, force-plan, guidance-dependent, got \"telepathy\""));

  // A study file: only simulated subjects on the simulated pen.
  test::TempDir dir;
  const auto write = [&](const std::string& name, const std::string& device, const std::string& participant) {
    const auto file = dir / name;
    const std::string text = fmt::format(R"({{"name": "t", "skill": "na", "experts": {{"na": "{}"}},
      "modes": ["BASIC", "ALPHA"], "device": "{}", "subjects": [{{"id": "P1", "participant": "{}"}}]}})",
                                         (dir / "expert.csv").string(), device, participant);
    hattr::writeFileAtomically(file, text, hattr::Overwrite::kReplace);
    return file;
  };
  (void)writePaperStudy(dir.path(), {.subjects = 3});  // writes expert.csv
  EXPECT_THAT(message({.study = write("person.json", "sim://pen", "person")}),
              HasSubstr("subject P1 is a \"person\" participant: a power analysis replaces the subjects"));
  EXPECT_THAT(message({.study = write("udp.json", "udp://127.0.0.1:9", "simulated")}),
              HasSubstr("a power analysis simulates its studies: expected a sim:// device"));
}

// Clopper–Pearson intervals as R's binom.test (R 4.2, printed with %.17g).
TEST(PowerSummary, ClopperPearsonIntervalsAreRsBinomTest) {
  struct Case {
    int k, n;
    double confidence, lower, upper;
  };
  const Case cases[] = {{7, 20, 0.95, 0.15390920478454115, 0.59218853453282816},
                        {0, 10, 0.95, 0.0, 0.30849710781876083},
                        {10, 10, 0.95, 0.69150289218123917, 1.0},
                        {1, 200, 0.95, 0.00012658102786701841, 0.02754189845720556},
                        {123, 200, 0.95, 0.54376130721685478, 0.68277547463713262},
                        {3, 8, 0.90, 0.1111127066076292, 0.71075918349819056}};
  for (const auto& c : cases) {
    const analysis::Proportion p = analysis::clopperPearson(c.k, c.n, c.confidence);
    EXPECT_DOUBLE_EQ(p.estimate, static_cast<double>(c.k) / c.n);
    EXPECT_NEAR(p.lower, c.lower, 1e-12) << c.k << "/" << c.n;
    EXPECT_NEAR(p.upper, c.upper, 1e-12) << c.k << "/" << c.n;
  }
  EXPECT_THROW((void)analysis::clopperPearson(3, 2), InputError);
  EXPECT_THROW((void)analysis::clopperPearson(0, 0), InputError);
}

/// A plan of three modes and synthetic outcomes: replicate r's p values from a seeded
/// generator, with NaN (no variance) in some.
report::PowerPlan syntheticPlan(int replicates) {
  report::PowerPlan plan;
  plan.study = {{"name", "synthetic"}};
  plan.modes = {"BASIC", "PCONTROL", "ALPHA"};
  plan.subject_counts = {6, 10};
  plan.replicates = replicates;
  plan.seed = 3;
  plan.alpha = 0.05;
  return plan;
}

std::vector<report::ReplicateOutcome> syntheticOutcomes(const report::PowerPlan& plan) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> p(0.0, 0.2);
  std::vector<report::ReplicateOutcome> out;
  for (int r = 0; r < plan.replicates; ++r) {
    report::ReplicateOutcome o{r, {}};
    for (std::size_t d = 0; d < plan.subject_counts.size(); ++d) {
      std::array<report::MetricOutcome, 2> design;
      for (auto& m : design) {
        m.p_mode = r % 7 == 3 ? std::nan("") : p(rng);
        m.partial_eta_sq = r % 5 == 1 ? std::nan("") : p(rng);
        for (int k = 0; k < 3; ++k) m.p_pairs.push_back(p(rng));
      }
      o.designs.push_back(design);
    }
    out.push_back(o);
  }
  return out;
}

TEST(PowerSummary, CountsPBelowAlphaAndAveragesTheEffectSizeLeavingNaNOut) {
  const report::PowerPlan plan = syntheticPlan(20);
  std::vector<report::ReplicateOutcome> outcomes = syntheticOutcomes(plan);
  // Count by hand for the second design's force.
  int found = 0, eta_n = 0;
  double eta = 0.0;
  for (const auto& o : outcomes) {
    const auto& m = o.designs[1][1];
    found += m.p_mode < 0.05 ? 1 : 0;  // NaN compares false: not significant
    if (!std::isnan(m.partial_eta_sq)) eta += m.partial_eta_sq, ++eta_n;
  }
  std::reverse(outcomes.begin(), outcomes.end());  // any order
  const report::PowerTable table = report::summarizePower(plan, outcomes);
  ASSERT_EQ(table.rows.size(), 4u);
  const report::PowerRow& row = table.rows[3];
  EXPECT_EQ(row.subjects, 10);
  EXPECT_EQ(row.metric, "force");
  EXPECT_EQ(row.power.successes, found);
  EXPECT_EQ(row.power.trials, 20);
  EXPECT_GT(found, 0);
  EXPECT_LT(found, 20);
  EXPECT_DOUBLE_EQ(row.mean_partial_eta_sq, eta / eta_n);
  ASSERT_EQ(row.pairs.size(), 3u);
  EXPECT_EQ(row.pairs[2].pair, "PCONTROL-ALPHA");

  // A replicate missing, twice, or out of the plan is refused.
  outcomes.pop_back();
  EXPECT_THROW((void)report::summarizePower(plan, outcomes), InputError);
  outcomes.push_back(outcomes.front());
  EXPECT_THROW((void)report::summarizePower(plan, outcomes), InputError);
}

// Shards merge to exactly what one process summarizes: the outcomes go through JSON exactly.
TEST(PowerShards, MergedShardsEqualTheWholeRunAndForeignOrMissingShardsAreRefused) {
  test::TempDir dir;
  const report::PowerPlan plan = syntheticPlan(10);
  const std::vector<report::ReplicateOutcome> all = syntheticOutcomes(plan);
  const nlohmann::json whole = report::powerTableToJson(report::summarizePower(plan, all));
  std::vector<std::filesystem::path> files;
  for (int shard = 0; shard < 3; ++shard) {
    std::vector<report::ReplicateOutcome> mine;
    for (int r = shard; r < plan.replicates; r += 3) mine.push_back(all[static_cast<std::size_t>(r)]);
    files.push_back(dir / fmt::format("shard-{}.json", shard));
    hattr::writeFileAtomically(files.back(), report::powerShardToJson(plan, shard, 3, mine).dump(1),
                            hattr::Overwrite::kReplace);
  }
  EXPECT_EQ(report::powerTableToJson(report::mergePowerShards(files)).dump(), whole.dump());

  // The flat encoding MPI gathers is exact too.
  std::vector<double> flat;
  report::encodeOutcome(all[3], flat);
  ASSERT_EQ(flat.size(), report::encodedOutcomeSize(plan));
  const report::ReplicateOutcome back = report::decodeOutcome(plan, flat);
  EXPECT_EQ(back.replicate, 3);
  EXPECT_TRUE(std::isnan(back.designs[0][0].p_mode));
  EXPECT_EQ(back.designs[1][1].p_pairs, all[3].designs[1][1].p_pairs);

  const auto message = [](const std::vector<std::filesystem::path>& f) {
    try {
      (void)report::mergePowerShards(f);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_THAT(message({files[0], files[2]}), HasSubstr("power merge: 7 of 10 replicates are in the files; missing: 1, 4, 7"));
  EXPECT_THAT(message({files[0], files[1], files[1]}), HasSubstr("shard-1.json: replicate 1 is also in"));
  report::PowerPlan other = plan;
  other.alpha = 0.01;
  hattr::writeFileAtomically(dir / "other.json", report::powerShardToJson(other, 0, 1, {}).dump(), hattr::Overwrite::kReplace);
  EXPECT_THAT(message({files[0], dir / "other.json"}), HasSubstr("other.json: another power analysis than"));
  hattr::writeFileAtomically(dir / "study.json", "{\"name\": \"x\"}", hattr::Overwrite::kReplace);
  EXPECT_THAT(message({dir / "study.json"}), HasSubstr("study.json: not a power shard"));
}

}  // namespace
}  // namespace hattr::sim
