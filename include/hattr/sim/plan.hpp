#pragma once
/// The designs a study plan searches (docs/simulation.md, "Planning a study"): for a number of
/// subjects and a replicate, the p of the comparison asked, the same wherever it is computed.
/// A simulated study (sim::PowerStudy, analyzed by its ANOVA or the design report's mixed model) or the built-in
/// calibration design, whose outcome is normal with a given effect size so that its analysis
/// is a t-test with a known power (R's power.t.test). report/plan.hpp searches over them.

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "hattr/sim/power.hpp"

namespace hattr::sim {

/// A design a plan runs replicates of.
class PlanDesign {
 public:
  virtual ~PlanDesign() = default;
  /// What makes its replicates the same: a plan's state keeps it, a resume must match it.
  [[nodiscard]] virtual nlohmann::json identity() const = 0;
  [[nodiscard]] virtual std::string label() const = 0;
  /// Between-subjects groups: a design of N has N per group.
  [[nodiscard]] virtual int groups() const = 0;
  /// One subject's lab time [s]; NaN where none is known.
  [[nodiscard]] virtual double labSecondsPerSubject() const = 0;
  /// The comparison's p for each replicate (NaN: nothing to test), each depending only on the
  /// design, `subjects` and the replicate. `progress`: the replicates run so far.
  [[nodiscard]] virtual std::vector<double> pValues(int subjects, std::span<const int> replicates,
                                                    const std::function<void(double)>& progress) const = 0;
};

/// The analysis a plan's replicates run: sim power's ANOVA, or the design report's linear mixed
/// model of the compared trials (report/design_models.cpp's formula).
enum class PlanAnalysis { kAnova, kMixed };
[[nodiscard]] PlanAnalysis parsePlanAnalysis(std::string_view text, std::string_view where);
[[nodiscard]] const char* planAnalysisName(PlanAnalysis analysis);

/// The outcome a plan compares: "shape" (the trajectory's DTW cost), "force" (the haptic
/// profile's) or a kinematic measure (analysis::kinematicsNames()). Throws InputError for another.
void checkPlanOutcome(std::string_view outcome, std::string_view where);

/// How one replicate's analyzed trials are compared.
struct TrialsComparison {
  PlanAnalysis analysis = PlanAnalysis::kAnova;
  std::string outcome = "shape";  ///< as checkPlanOutcome
  bool between_groups = false;    ///< the conditions are groups, a subject in one
  /// Empty: the conditions' effect; else the pair's difference (Tukey-adjusted over all the
  /// conditions present).
  std::string pair_a, pair_b;
};

/// The comparison's p in one replicate's analyzed trials (trials whose outcome is not finite
/// left out); NaN when the analysis gives none (too few trials, an unbalanced ANOVA, a model
/// that does not fit).
/// - ANOVA, within subjects: condition × subject with subject random and the trials as
///   replicates (the mode effect against condition:subject), Tukey HSD for a pair: sim
///   power's analysis to the bit. Between groups: the one-way ANOVA of the subjects' means and
///   Tukey HSD.
/// - Mixed: `y ~ condition + (1 | subject)`, with `+ (1 | subject:condition)` where subjects
///   did several conditions several times each; the effect's Satterthwaite F test (lmerTest's
///   anova), a pair's Satterthwaite t with the Tukey adjustment over the k conditions
///   (P(Q_k,df > √2·|t|), as emmeans' pairs).
[[nodiscard]] double comparisonP(std::span<const report::AnalyzedTrial> trials, const TrialsComparison& how);

struct StudyPlanOptions {
  /// The study, seed, α, threads, phase, hypothesis and scratch as for a power analysis; its
  /// designs are replaced by one of `max_subjects` and its replicates by `max_replicates`.
  PowerOptions power;
  int max_subjects = 200;
  int max_replicates = 400;
  /// "mode": the effect of the modes (or groups); "A-B": Tukey's pair of A and B.
  std::string comparison = "mode";
  std::string outcome = "shape";  ///< as checkPlanOutcome
  PlanAnalysis analysis = PlanAnalysis::kAnova;
  double session_setup_s = 600.0;  ///< a session's lab time besides its trials [s]
};

/// A simulated study to plan. Throws InputError for bad options, a study a power analysis
/// refuses, or a comparison of a strategy (or group) the study does not have.
[[nodiscard]] std::unique_ptr<PlanDesign> makeStudyPlanDesign(const StudyPlanOptions& options);

struct CalibrationOptions {
  bool paired = false;       ///< paired (one group, two conditions) or two independent groups
  double effect_size = 0.5;  ///< Cohen's d: the mean difference over the SD (of the differences, paired)
  std::uint64_t seed = 1;
};

/// The calibration design: replicate r's subject i has values drawn from its own seeded stream
/// (a larger design's first subjects are a smaller one's), analyzed by the ANOVA the plans of
/// studies use: the two groups' one-way ANOVA (F = t², the two-sample t-test) or the mode ×
/// subject ANOVA with one value per cell (F = t², the paired t-test). Throws InputError unless
/// 0 < |effect size| <= 10.
[[nodiscard]] std::unique_ptr<PlanDesign> makeCalibrationDesign(const CalibrationOptions& options);

}  // namespace hattr::sim
