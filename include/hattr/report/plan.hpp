#pragma once
/// Planning a study by simulation (docs/simulation.md, "Planning a study"): the smallest
/// design that reaches a target power, found by a search that spends simulated studies where
/// the decision is. This is the search's bookkeeping, free of any simulation: it says which
/// replicates of which design it needs next, from the outcomes it has been given, so the same
/// outcomes always lead to the same designs and the same answer (in one process, on MPI ranks,
/// in shards, after a kill and a resume). sim/plan.hpp runs the replicates. Offline code.
///
/// The search, over the designs min, min + step, ... up to max subjects: the largest first
/// (when it falls short, no design does), then the smallest (when it suffices, it is the
/// answer), then bisection between a design judged below the target and one judged above it.
/// Power is assumed not to fall as subjects are added. Each design gets replicates a batch at a
/// time, in order (0, 1, ...); after each batch its exact (Clopper–Pearson) interval at
/// 1 − (1 − confidence) / looks, looks = max_replicates / batch (Bonferroni over the looks),
/// decides it once the interval excludes the target. A design that has had max_replicates
/// without a decision is undecided and judged by its estimate.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "hattr/analysis/proportion.hpp"

namespace hattr::report {

struct PlanSearchOptions {
  int min_subjects = 3;
  int max_subjects = 200;
  int step = 1;               ///< the designs: min, min + step, ... (max is one of them when on the grid)
  double target = 0.8;        ///< the power sought, in (0, 1)
  int batch = 10;             ///< replicates a design gets at each look
  int max_replicates = 400;   ///< a design's most replicates (a whole number of batches)
  double confidence = 0.95;   ///< of each design's decision over all its looks
  /// Throws InputError naming a bad field.
  void check() const;
  [[nodiscard]] int looks() const noexcept { return max_replicates / batch; }
  [[nodiscard]] bool operator==(const PlanSearchOptions&) const = default;
};

enum class PlanDecision {
  kBelow,      ///< the interval lies below the target
  kAbove,      ///< the interval lies above it
  kUndecided,  ///< max_replicates without either: judged by the estimate
};
[[nodiscard]] const char* decisionName(PlanDecision decision);

/// A design the search has decided (or left undecided).
struct PlanPoint {
  int subjects = 0;
  analysis::Proportion power;  ///< over its replicates, 95 % Clopper–Pearson
  PlanDecision decision = PlanDecision::kUndecided;
  /// The decision, or for an undecided design its estimate, is at or above the target.
  [[nodiscard]] bool reaches(double target) const;
};

/// The undecided designs the search runs on each side of its answer, looking for one decided
/// there (the Monte Carlo range's end), before it lets the range end at a design decided farther
/// out (or the grid's end).
inline constexpr int kMostUndecidedWalked = 4;

/// Replicates [first, first + count) of the design of `subjects`.
struct PlanRequest {
  int subjects = 0;
  int first = 0;
  int count = 0;
  [[nodiscard]] bool operator==(const PlanRequest&) const = default;
};

struct PlanSearchResult {
  std::vector<PlanPoint> points;  ///< the designs decided, ascending subjects
  /// The smallest design judged to reach the target; none when the largest falls short.
  std::optional<int> answer;
  /// The Monte Carlo range of the answer: from one step above the largest design decided
  /// below the target to the smallest decided above it (the grid's ends where none is).
  int range_low = 0;
  int range_high = 0;
  int replicates = 0;             ///< replicates the decisions used, over the designs
  [[nodiscard]] const PlanPoint& point(int subjects) const;
};

/// The search's state: the outcomes it has (significant or not, per design and replicate).
class PlanSearch {
 public:
  explicit PlanSearch(const PlanSearchOptions& options);
  [[nodiscard]] const PlanSearchOptions& options() const noexcept { return options_; }
  /// The replicates needed next; none once the search has its answer.
  [[nodiscard]] std::optional<PlanRequest> next() const;
  /// An outcome; throws InputError for a design off the grid, a replicate out of range, or an
  /// outcome that contradicts one recorded before.
  void record(int subjects, int replicate, bool significant);
  [[nodiscard]] bool has(int subjects, int replicate) const;
  /// The result; throws std::logic_error while next() still asks for replicates.
  [[nodiscard]] PlanSearchResult result() const;

 private:
  /// The design's point once decided, else the batch it needs.
  struct Status {
    std::optional<PlanPoint> point;
    std::optional<PlanRequest> request;
  };
  [[nodiscard]] Status status(int subjects) const;
  /// Walks the search from its start over the outcomes known: the batch it needs next, or none
  /// with `answer` set (when a design reaches the target). `visited` gets each design decided,
  /// ascending.
  [[nodiscard]] std::optional<PlanRequest> walk(std::vector<PlanPoint>* visited, std::optional<int>* answer) const;
  [[nodiscard]] int gridSize() const noexcept;
  [[nodiscard]] int gridValue(int index) const noexcept { return options_.min_subjects + index * options_.step; }

  PlanSearchOptions options_;
  std::map<int, std::vector<signed char>> outcomes_;  ///< subjects -> per replicate: -1 unknown, 0, 1
};

[[nodiscard]] nlohmann::json planSearchOptionsToJson(const PlanSearchOptions& options);

/// One search of a plan: a design (a study under a hypothesis, or the calibration design).
struct PlanSearchReport {
  std::string label;              ///< e.g. "the paper's study (11 + 11 trials), force-plan"
  std::string hypothesis;         ///< empty: none (the calibration design)
  nlohmann::json design;          ///< what makes its replicates the same
  int groups = 1;                 ///< subjects in all = groups × subjects per group
  double lab_s_per_subject = 0.0; ///< NaN: not known (the calibration design)
  int max_subjects = 0;           ///< the largest design the limits allow (per group)
  PlanSearchResult result;
  [[nodiscard]] double labHours(int subjects) const;
};

/// A whole plan: what it compares, its searches, and per hypothesis the cheapest answer.
struct PlanReport {
  nlohmann::json plan;                     ///< comparison, outcome, analysis, α, search options, seed
  std::vector<PlanSearchReport> searches;
  std::vector<std::string> skipped;        ///< designs the limits ruled out, each with its reason
  /// Per hypothesis (in the searches' order), the index of the search whose answer costs the
  /// fewest lab hours (subjects where no time is known); none when no search reaches the target.
  [[nodiscard]] std::vector<std::pair<std::string, std::optional<std::size_t>>> answers() const;
};

/// "no design within 200 subjects reaches 80 % power: best 43 % (38–48 %) at 200", or the answer.
[[nodiscard]] std::string planSearchSentence(const PlanSearchReport& search, double target);
[[nodiscard]] nlohmann::json planReportToJson(const PlanReport& report);
[[nodiscard]] std::string planReportText(const PlanReport& report);
/// A self-contained HTML page: each search's power curve with intervals, the answers, the lab time.
void writePlanPage(const PlanReport& report, const std::filesystem::path& file);

}  // namespace hattr::report
