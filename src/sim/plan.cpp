#include "hattr/sim/plan.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <numbers>

#include <fmt/format.h>

#include "hattr/analysis/anova.hpp"
#include "hattr/analysis/kinematics.hpp"
#include "hattr/analysis/lmm.hpp"
#include "hattr/analysis/studentized_range.hpp"
#include "hattr/core/error.hpp"
#include "hattr/report/design_analysis.hpp"
#include "random_internal.hpp"

namespace hattr::sim {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Where the comparison's p is in a replicate's outcome: the effect, or a Tukey pair.
struct ComparisonIndex {
  bool effect = true;
  std::size_t pair = 0;
};

/// "mode", or "A-B" with A and B among the plan's modes (either order).
ComparisonIndex resolveComparison(const std::string& comparison, const report::PowerPlan& plan) {
  if (comparison == "mode") return {};
  const std::vector<std::string> pairs = plan.pairs();
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    const std::size_t dash = pairs[k].find('-');
    const std::string reversed = pairs[k].substr(dash + 1) + "-" + pairs[k].substr(0, dash);
    if (comparison == pairs[k] || comparison == reversed) return {false, k};
  }
  HATTR_THROW_UNLESS(false, "--compare {}: expected \"mode\" or two of the design's {} joined by '-' (e.g. {}), got "
                     "\"{}\"", comparison, fmt::join(plan.modes, ", "), pairs.empty() ? "A-B" : pairs.front(),
                     comparison);
  return {};
}

/// A trial's value of the outcome compared.
double outcomeOf(const report::AnalyzedTrial& t, const std::string& outcome) {
  if (outcome == "shape") return t.shape;
  if (outcome == "force") return t.force;
  return t.kinematic;
}

/// The Tukey-adjusted p of the pair asked, named either way round; NaN when Tukey has none.
double tukeyPairP(const analysis::TukeyResult& tukey, const TrialsComparison& how) {
  for (const auto& c : tukey.comparisons) {
    if ((c.level == how.pair_a && c.other_level == how.pair_b) || (c.level == how.pair_b && c.other_level == how.pair_a)) {
      return c.p_adjusted;
    }
  }
  return kNaN;
}

/// A trial's subject, condition and outcome, column by column.
struct TrialColumns {
  std::vector<std::string> subject, condition;
  std::vector<double> value;
};
TrialColumns columnsOf(const std::vector<const report::AnalyzedTrial*>& trials, const std::string& outcome) {
  TrialColumns c;
  for (const auto* t : trials) {
    c.subject.push_back(t->subject);
    c.condition.push_back(t->condition);
    c.value.push_back(outcomeOf(*t, outcome));
  }
  return c;
}

/// Conditions within subjects: condition × subject, subject random (report::analyzeMetric's).
double withinSubjectsAnovaP(const std::vector<const report::AnalyzedTrial*>& trials, const TrialsComparison& how) {
  TrialColumns c = columnsOf(trials, how.outcome);
  const analysis::TwoWayData all{"mode", "subject", std::move(c.condition), std::move(c.subject), std::move(c.value)};
  const analysis::AnovaOptions mixed{.b_random = true};
  const analysis::AnovaTable table = analysis::twoWayAnova(all, mixed);
  if (how.pair_a.empty()) return table.row("mode").p;
  if (table.a_levels.size() < 2 || table.b_levels.size() < 3) return kNaN;
  return tukeyPairP(analysis::tukeyHsd(all, analysis::Factor::kA, mixed), how);
}

/// Groups: the one-way ANOVA of each subject's mean (report::groupSubjectMeans's), Tukey HSD.
double betweenGroupsAnovaP(const std::vector<const report::AnalyzedTrial*>& trials, const TrialsComparison& how) {
  const TrialColumns c = columnsOf(trials, how.outcome);
  const analysis::OneWayData data = report::groupSubjectMeans(c.subject, c.condition, c.value);
  if (how.pair_a.empty()) return analysis::oneWayAnova(data).row("group").p;
  return tukeyPairP(analysis::tukeyHsdOneWay(data), how);
}

/// The design report's mixed model of the trials (report::fitConditionModel).
double mixedP(const std::vector<const report::AnalyzedTrial*>& trials, const TrialsComparison& how) {
  const TrialColumns c = columnsOf(trials, how.outcome);
  const std::set<std::string> conditions(c.condition.begin(), c.condition.end());
  if (conditions.size() < 2) return kNaN;
  const std::string reference = how.pair_a.empty() ? *conditions.begin() : how.pair_a;
  const analysis::LmmFit fit =
      report::fitConditionModel(c.subject, c.condition, c.value, "condition", "y", reference, "the compared trials");
  if (how.pair_a.empty()) {
    for (const auto& term : fit.terms) {
      if (term.term == "condition") return term.p;
    }
    return kNaN;
  }
  for (const auto& coefficient : fit.fixed) {
    if (coefficient.name == "condition" + how.pair_b) {
      return analysis::studentizedRangeUpperTail(std::numbers::sqrt2 * std::abs(coefficient.t),
                                                 static_cast<int>(conditions.size()), coefficient.df);
    }
  }
  return kNaN;
}

/// Whether a plan's p is sim power's own (its ANOVA of shape or force), else computed from the
/// replicate's analyzed trials.
bool powerAnalyzes(const StudyPlanOptions& o) {
  return o.analysis == PlanAnalysis::kAnova && (o.outcome == "shape" || o.outcome == "force");
}

/// A simulated study: PowerStudy's replicates of one design at a time.
class StudyPlanDesign final : public PlanDesign {
 public:
  explicit StudyPlanDesign(const StudyPlanOptions& o) : options_(o), study_(powerOptions(o)) {
    comparison_ = resolveComparison(o.comparison, study_.plan());
    HATTR_THROW_UNLESS(o.session_setup_s >= 0.0 && std::isfinite(o.session_setup_s),
                       "--session-setup: expected a time of at least 0 minutes, got {} s", o.session_setup_s);
    lab_s_ = study_.labSecondsPerSubject(o.session_setup_s);
    trials_ = {.analysis = o.analysis, .outcome = o.outcome, .between_groups = study_.groups() > 1};
    if (!comparison_.effect) {
      const std::string pair = study_.plan().pairs().at(comparison_.pair);
      trials_.pair_a = pair.substr(0, pair.find('-'));
      trials_.pair_b = pair.substr(pair.find('-') + 1);
    }
  }

  nlohmann::json identity() const override {
    const report::PowerPlan& plan = study_.plan();
    nlohmann::json identity{{"study", plan.study},
                            {"modes", plan.modes},
                            {"seed", plan.seed},
                            {"comparison", options_.comparison},
                            {"outcome", options_.outcome}};
    // Only when not sim power's ANOVA: a state folder of an ANOVA plan from before still matches.
    if (options_.analysis != PlanAnalysis::kAnova) identity["analysis"] = planAnalysisName(options_.analysis);
    return identity;
  }

  std::string label() const override {
    const report::PowerPlan& plan = study_.plan();
    const std::string trainee = plan.study.value("trainee", std::string("?"));
    if (options_.power.study.empty()) {
      return fmt::format("the paper's study ({}, {} + {} trials per mode), {}", options_.power.glyph,
                         options_.power.training_trials, options_.power.recall_trials, trainee);
    }
    return fmt::format("{} ({}), {}", plan.study.value("name", options_.power.study.filename().string()),
                       options_.power.study.filename().string(), trainee);
  }

  int groups() const override { return study_.groups() > 1 ? study_.groups() : 1; }
  double labSecondsPerSubject() const override { return lab_s_; }

  std::vector<double> pValues(int subjects, std::span<const int> replicates,
                              const std::function<void(double)>& progress) const override {
    const std::vector<report::ReplicateOutcome> outcomes = study_.runDesign(replicates, subjects, progress);
    std::vector<double> p;
    p.reserve(outcomes.size());
    const std::size_t metric = options_.outcome == "shape" ? 0 : 1;
    for (const auto& o : outcomes) {
      if (!powerAnalyzes(options_)) {
        p.push_back(comparisonP(o.trials, trials_));
        continue;
      }
      const report::MetricOutcome& m = o.designs.front()[metric];
      p.push_back(comparison_.effect ? m.p_mode : m.p_pairs.at(comparison_.pair));
    }
    return p;
  }

 private:
  static PowerOptions powerOptions(const StudyPlanOptions& o) {
    PowerOptions p = o.power;
    HATTR_THROW_UNLESS(o.max_subjects >= 3 && o.max_subjects <= 1000,
                       "--max-subjects: expected 3 to 1000 subjects (per group), got {}", o.max_subjects);
    p.subject_counts = {o.max_subjects};
    p.replicates = o.max_replicates;
    checkPlanOutcome(o.outcome, "--outcome");
    p.keep_trials = !powerAnalyzes(o);
    // Only the outcome's channels are scored (the paper's form; the same bits for it).
    p.score_shape = o.outcome == "shape";
    p.score_force = o.outcome == "force";
    if (o.outcome != "shape" && o.outcome != "force") p.kinematic = o.outcome;
    return p;
  }

  StudyPlanOptions options_;
  PowerStudy study_;
  ComparisonIndex comparison_;
  TrialsComparison trials_;
  double lab_s_ = 0.0;
};

/// Normal draws from a SplitMix64 stream (a cheap generator per subject: designs need millions).
class SubjectStream {
 public:
  explicit SubjectStream(std::uint64_t seed) : state_(seed) {}
  double normal() noexcept {
    const double radius = std::sqrt(-2.0 * std::log(uniform()));
    return radius * std::cos(2.0 * std::numbers::pi * uniform());
  }

 private:
  double uniform() noexcept {
    state_ += 0x9E3779B97F4A7C15ULL;
    return (static_cast<double>(detail::splitMix64(state_) >> 11) + 0.5) * 0x1.0p-53;
  }
  std::uint64_t state_;
};

/// The calibration design (makeCalibrationDesign).
class CalibrationDesign final : public PlanDesign {
 public:
  explicit CalibrationDesign(const CalibrationOptions& o) : options_(o) {
    HATTR_THROW_UNLESS(std::isfinite(o.effect_size) && o.effect_size != 0.0 && std::abs(o.effect_size) <= 10.0,
                       "--effect-size: expected a Cohen's d with 0 < |d| <= 10, got {}", o.effect_size);
  }

  nlohmann::json identity() const override {
    return {{"calibration", options_.paired ? "paired" : "two-sample"},
            {"effect_size", options_.effect_size},
            {"seed", options_.seed}};
  }
  std::string label() const override {
    return fmt::format("calibration: {} t-test, d = {}", options_.paired ? "paired" : "two-sample", options_.effect_size);
  }
  int groups() const override { return options_.paired ? 1 : 2; }
  double labSecondsPerSubject() const override { return kNaN; }

  std::vector<double> pValues(int subjects, std::span<const int> replicates,
                              const std::function<void(double)>& progress) const override {
    std::vector<double> p;
    p.reserve(replicates.size());
    for (const int r : replicates) {
      p.push_back(options_.paired ? pairedP(subjects, r) : twoSampleP(subjects, r));
      if (progress) progress(static_cast<double>(p.size()));
    }
    return p;
  }

 private:
  /// Subject i's (from 1) stream in replicate r, for one group (0 or 1).
  SubjectStream stream(int replicate, int subject, int group) const {
    const std::uint64_t id = (static_cast<std::uint64_t>(replicate) << 24) ^ (static_cast<std::uint64_t>(subject) << 1) ^
                             static_cast<std::uint64_t>(group);
    return SubjectStream(detail::streamSeed(options_.seed, id));
  }

  /// Two groups of n, N(0, 1) and N(d, 1): the one-way ANOVA's p (the pooled two-sample t-test's).
  double twoSampleP(int n, int replicate) const {
    analysis::OneWayData data;
    data.group.reserve(2 * static_cast<std::size_t>(n));
    data.y.reserve(2 * static_cast<std::size_t>(n));
    for (int g = 0; g < 2; ++g) {
      for (int i = 1; i <= n; ++i) {
        data.group.emplace_back(g == 0 ? "A" : "B");
        data.y.push_back(stream(replicate, i, g).normal() + (g == 0 ? 0.0 : options_.effect_size));
      }
    }
    return analysis::oneWayAnova(data).row("group").p;
  }

  /// n subjects in both conditions, their difference N(d, 1) around a subject effect: the mode ×
  /// subject ANOVA's p with one value per cell (the paired t-test's).
  double pairedP(int n, int replicate) const {
    analysis::TwoWayData data;
    data.a_name = "mode";
    data.b_name = "subject";
    for (int i = 1; i <= n; ++i) {
      SubjectStream s = stream(replicate, i, 0);
      const double subject = s.normal();
      const std::string id = fmt::format("S{}", i);
      for (int c = 0; c < 2; ++c) {
        data.a.emplace_back(c == 0 ? "A" : "B");
        data.b.push_back(id);
        // Each condition's error has SD 1/√2, so that their difference has SD 1.
        data.y.push_back(subject + (c == 0 ? 0.0 : options_.effect_size) + s.normal() * std::numbers::sqrt2 / 2.0);
      }
    }
    return analysis::twoWayAnova(data, {.b_random = true}).row("mode").p;
  }

  CalibrationOptions options_;
};

}  // namespace

PlanAnalysis parsePlanAnalysis(std::string_view text, std::string_view where) {
  if (text == "anova") return PlanAnalysis::kAnova;
  if (text == "mixed") return PlanAnalysis::kMixed;
  HATTR_THROW_UNLESS(false, "{}: expected anova (sim power's) or mixed (the design report's linear mixed model), got "
                     "\"{}\"", where, text);
  return PlanAnalysis::kAnova;
}

const char* planAnalysisName(PlanAnalysis analysis) { return analysis == PlanAnalysis::kAnova ? "anova" : "mixed"; }

void checkPlanOutcome(std::string_view outcome, std::string_view where) {
  if (outcome == "shape" || outcome == "force") return;
  HATTR_THROW_UNLESS(analysis::isKinematicsName(outcome),
                     "{}: expected shape (the trajectory's DTW cost), force (the haptic profile's) or a kinematic "
                     "measure ({}), got \"{}\"", where, fmt::join(analysis::kinematicsNames(), ", "), outcome);
}

double comparisonP(std::span<const report::AnalyzedTrial> trials, const TrialsComparison& how) {
  std::vector<const report::AnalyzedTrial*> kept;
  for (const auto& t : trials) {
    if (std::isfinite(outcomeOf(t, how.outcome))) kept.push_back(&t);
  }
  try {
    if (how.analysis == PlanAnalysis::kMixed) return mixedP(kept, how);
    return how.between_groups ? betweenGroupsAnovaP(kept, how) : withinSubjectsAnovaP(kept, how);
  } catch (const InputError&) {  // data the analysis cannot take: no p, so not significant
    return kNaN;
  }
}

std::unique_ptr<PlanDesign> makeStudyPlanDesign(const StudyPlanOptions& options) {
  return std::make_unique<StudyPlanDesign>(options);
}

std::unique_ptr<PlanDesign> makeCalibrationDesign(const CalibrationOptions& options) {
  return std::make_unique<CalibrationDesign>(options);
}

}  // namespace hattr::sim
