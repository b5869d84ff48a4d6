#pragma once
/// The designs a study plan searches (docs/simulation.md, "Planning a study"): for a number of
/// subjects and a replicate, the p of the comparison asked, the same wherever it is computed.
/// A simulated study (sim::PowerStudy, its analysis the design report's ANOVA) or the built-in
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

/// The outcome a plan compares.
enum class PlanOutcome { kShape, kForce };
[[nodiscard]] PlanOutcome parsePlanOutcome(std::string_view text, std::string_view where);
[[nodiscard]] const char* planOutcomeName(PlanOutcome outcome);

struct StudyPlanOptions {
  /// The study, seed, α, threads, phase, hypothesis and scratch as for a power analysis; its
  /// designs are replaced by one of `max_subjects` and its replicates by `max_replicates`.
  PowerOptions power;
  int max_subjects = 200;
  int max_replicates = 400;
  /// "mode": the effect of the modes (or groups); "A-B": Tukey's pair of A and B.
  std::string comparison = "mode";
  PlanOutcome outcome = PlanOutcome::kShape;
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
