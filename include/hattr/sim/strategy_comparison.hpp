#pragma once
/// Strategies compared in silico (`hattr sim compare-strategies`, docs/simulation.md "Comparing
/// strategies"): one design run once per learning hypothesis with a group of simulated subjects
/// per strategy (each block of the design's group strategy takes the group's), analyzed per phase
/// (training, post-test, retention, transfer, ...): each subject's mean cost, each strategy's
/// mean over its subjects with a 95 % interval, and a one-way ANOVA between the strategies; and
/// each phase after a baseline of its skill again as each subject's change from its baseline
/// ("post-test − baseline": what it learned, free of who it was to begin with). An
/// A/A check runs the same design with every guidance off under other seeds, so the strategies
/// are labels only: how often it finds a difference between them is the false-positive rate the
/// table's p-values stand against.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "hattr/guidance/training_guidance.hpp"
#include "hattr/report/design_analysis.hpp"
#include "hattr/sim/trainee_model.hpp"

namespace hattr::sim {

struct StrategyComparisonOptions {
  /// The design: a study file of groups and sessions (its groups replaced by one per strategy,
  /// its subjects by simulated ones), or when empty the shipped design `design`.
  std::filesystem::path study;
  std::string design = "groups-retention";
  /// The strategies compared (none mentored); empty: every one that is not mentored.
  std::vector<guidance::TrainingMode> strategies;
  /// The learning hypotheses; empty: every one.
  std::vector<LearningHypothesis> hypotheses;
  int subjects = 6;          ///< per strategy
  int max_trials = 0;        ///< each block at most this many trials (0: as designed)
  std::uint64_t seed = 1;    ///< subject i of a study: seed·1000 + i; A/A study k: seed + k
  int aa_seeds = 3;
  int threads = 0;           ///< subjects simulated at once, and scoring threads (0: the hardware's)
  /// Where the studies are made (each removed once analyzed); empty: the system's temporary folder.
  std::filesystem::path scratch;
  /// After each study: studies done, of all.
  std::function<void(int done, int total, std::string_view what)> progress;
};

/// One phase (of one skill) as the strategies came out of it.
struct PhaseComparison {
  std::string phase;
  std::string skill;
  /// Per strategy, in the options' order: its subjects' mean cost with its interval.
  std::vector<report::SubjectMean> shape, force;
  double p_shape = 0.0;      ///< the one-way ANOVA's p between the strategies
  double p_force = 0.0;
  int aa_significant_shape = 0;  ///< A/A studies with p < 0.05 on this phase
  int aa_significant_force = 0;
};

struct HypothesisStrategies {
  LearningHypothesis hypothesis = LearningHypothesis::kPositionPlan;
  std::vector<PhaseComparison> phases;  ///< in the design's order, then the changes from baseline
};

struct StrategyComparison {
  std::vector<guidance::TrainingMode> strategies;
  std::string design;                   ///< the design's name (or its file)
  int subjects = 0;
  int aa_seeds = 0;
  std::uint64_t seed = 0;
  std::vector<HypothesisStrategies> hypotheses;
};

/// Runs the comparison (1 + aa_seeds studies per hypothesis). InputError for bad options, a
/// design whose blocks never use the group's strategy, or a mentored strategy.
StrategyComparison compareStrategies(const StrategyComparisonOptions& options);

/// {design, subjects, seed, aa_seeds, alpha, strategies [name], hypotheses [{hypothesis, phases
/// [{phase, skill, p_shape, p_force, aa {significant_shape, significant_force}, strategies
/// [{strategy, shape {subjects, mean, ci}, force {...}}]}]}]}.
nlohmann::json strategyComparisonToJson(const StrategyComparison& comparison);

}  // namespace hattr::sim
