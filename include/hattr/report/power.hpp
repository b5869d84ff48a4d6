#pragma once
/// A power analysis's results (docs/simulation.md, "Power analysis"): what each simulated
/// replicate of a study found, and over the replicates, for each design (number of
/// subjects), the probability that the paper's analysis finds the mode effect and each Tukey
/// pairwise difference at α, with its exact confidence interval, and the expected effect
/// size. sim::PowerStudy runs the replicates; this is their bookkeeping: exact encodings
/// (so replicates run by MPI ranks or by shards merge to the bit), the summary, its JSON, text
/// and HTML page. Offline code.

#include <array>
#include <optional>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "hattr/analysis/proportion.hpp"
#include "hattr/report/study_analysis.hpp"

namespace hattr::report {

/// What a power analysis runs; equal plans give the same replicates.
struct PowerPlan {
  nlohmann::json study;              ///< the study's definition without its subjects and expert files
  std::vector<std::string> modes;    ///< the study's modes, in its order
  std::vector<int> subject_counts;   ///< the designs, ascending
  int replicates = 0;
  std::uint64_t seed = 1;            ///< replicate r is the study run with seed + r
  double alpha = 0.05;
  /// The Tukey pairs, "A-B" for modes i < j in the study's order.
  [[nodiscard]] std::vector<std::string> pairs() const;
  [[nodiscard]] bool operator==(const PowerPlan&) const = default;
};

/// The metrics, in the order of ReplicateOutcome's arrays.
inline constexpr std::array<const char*, 2> kPowerMetrics{"trajectory", "force"};

/// What one metric's analysis of one simulated study found (NaN where the analysis has no
/// value: no variance, or too few subjects for Tukey).
struct MetricOutcome {
  double p_mode = 0.0;           ///< the mode effect's p (mode × subject, subject random)
  double partial_eta_sq = 0.0;   ///< its partial η²
  std::vector<double> p_pairs;   ///< Tukey HSD adjusted p, PowerPlan::pairs order
};

/// One analyzed trial of a replicate's largest design, for analyses besides the power
/// analysis's own (a study plan's mixed model or kinematic outcome).
struct AnalyzedTrial {
  std::int64_t trial_id = 0;  ///< in the replicate's study
  std::string subject;
  std::string condition;  ///< the mode (or strategy) compared within subjects, or the subject's group
  int trial = 0;          ///< within its condition and phase, from 1
  double shape = 0.0;     ///< its costs, as analysis::TrialScore::shape() and force()
  double force = 0.0;
  double kinematic = std::numeric_limits<double>::quiet_NaN();  ///< the kinematic measure asked for (sim::PowerOptions::kinematic); NaN when none
};

/// One replicate: per design (PowerPlan::subject_counts order), trajectory then force.
struct ReplicateOutcome {
  int replicate = 0;
  std::vector<std::array<MetricOutcome, 2>> designs;
  /// The largest design's analyzed trials when sim::PowerOptions::keep_trials (not encoded).
  std::vector<AnalyzedTrial> trials;
};

/// Reads a metric's outcome from its analysis, pairs in the plan's order.
[[nodiscard]] MetricOutcome metricOutcome(const MetricResult& metric, const PowerPlan& plan);
/// The same from an effect's ANOVA row and its Tukey HSD (a between-groups design's one-way
/// analysis), pairs in the plan's order (NaN for a pair Tukey does not name).
[[nodiscard]] MetricOutcome metricOutcome(const analysis::AnovaRow& effect,
                                          const std::optional<analysis::TukeyResult>& tukey, const PowerPlan& plan);

/// A replicate as doubles (replicate index first), exact: MPI gathers these.
[[nodiscard]] std::size_t encodedOutcomeSize(const PowerPlan& plan);
void encodeOutcome(const ReplicateOutcome& outcome, std::vector<double>& out);
[[nodiscard]] ReplicateOutcome decodeOutcome(const PowerPlan& plan, std::span<const double> values);

struct PairPower {
  std::string pair;               ///< "BASIC-ALPHA"
  analysis::Proportion power;     ///< replicates with Tukey's adjusted p < α
};

struct PowerRow {
  int subjects = 0;
  std::string metric;
  analysis::Proportion power;        ///< replicates whose mode effect p < α (95 % CI)
  double mean_partial_eta_sq = 0.0;  ///< the expected effect size, over the replicates
  std::vector<PairPower> pairs;
};

struct PowerTable {
  PowerPlan plan;
  std::vector<PowerRow> rows;        ///< per design, trajectory then force
};

/// Summarizes the replicates 0 .. plan.replicates - 1, each present once, in any order;
/// throws InputError naming a missing, repeated or foreign replicate.
[[nodiscard]] PowerTable summarizePower(const PowerPlan& plan, std::vector<ReplicateOutcome> outcomes);

/// A shard's file: its plan, which replicates it holds (i of n) and their outcomes (exact).
nlohmann::json powerShardToJson(const PowerPlan& plan, int shard, int shards,
                                const std::vector<ReplicateOutcome>& outcomes);
/// Reads shard files and merges them; throws InputError (naming the file) for a file that
/// is not a shard, plans that differ, or replicates missing or held twice.
[[nodiscard]] PowerTable mergePowerShards(const std::vector<std::filesystem::path>& files);

[[nodiscard]] nlohmann::json powerTableToJson(const PowerTable& table);
[[nodiscard]] std::string powerTableText(const PowerTable& table);
/// A self-contained HTML page: the table and the power curves with their intervals.
void writePowerPage(const PowerTable& table, const std::filesystem::path& file);

}  // namespace hattr::report
