#pragma once
/// Study design by simulation: a power analysis (docs/simulation.md, "Power analysis").
/// Replicate r runs the study with simulated subjects through the real pipeline (the study
/// runner into a scratch database, the paper's analysis), the subjects seeded as the in-silico
/// study with seed + r. A design of groups and sessions is analyzed on one phase (its
/// retention by default): between groups, a one-way ANOVA of each subject's mean cost with
/// Tukey HSD between the groups, a design of N having N subjects per group; one group with
/// several strategies, the paper's mode × subject analysis of that phase's trials. Designs share their subjects (common random numbers): a design of N
/// subjects analyzes the replicate's first N, so the replicate runs only the largest design.
/// Replicates depend on (plan, r) alone: any split across threads, processes or machines
/// gives the same outcomes to the bit (report::summarizePower merges them).

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "hattr/report/power.hpp"
#include "hattr/report/study_analysis.hpp"
#include "hattr/session/study.hpp"
#include "hattr/session/trial.hpp"
#include "hattr/sim/scratch_folder.hpp"

namespace hattr::report {
struct DesignTrialScore;
}  // namespace hattr::report

namespace hattr::sim {

struct PowerOptions {
  /// A study file whose subjects are simulated: its modes, protocol, expert, pen (sim://)
  /// and world are used, its subjects replaced by each replicate's (their options, the
  /// first subject's). Empty: the paper's study in silico (glyph, trials below).
  std::filesystem::path study;
  std::string glyph = "na";         ///< the paper's study only
  int training_trials = 11;         ///< the paper's study only
  int recall_trials = 11;           ///< the paper's study only
  std::vector<int> subject_counts{6, 10, 20, 40};
  int replicates = 200;
  std::uint64_t seed = 1;
  double alpha = 0.05;
  int threads = 1;                  ///< subjects simulated at once, and scoring threads
  /// A design of groups and sessions only: the phase whose costs are compared. Empty: the
  /// design's retention, else its post-test, else its recall, else its last phase.
  std::string phase;
  /// A learning hypothesis ("force-plan", ...) for every subject, in place of the study's
  /// trainee model; empty: the study's (the paper's study: position-plan).
  std::string hypothesis;
  /// The paper's study only: the metrics a replicate analyzes. A study plan of one outcome scores
  /// only its channels (the DTW of the other's is not run) and the other's MetricOutcome is NaN;
  /// the one analyzed is the same to the bit; neither: no DTW at all (a plan of a kinematic
  /// outcome). A design of groups and sessions scores both.
  bool score_shape = true;
  bool score_force = true;
  /// Keep each replicate's analyzed trials of its largest design (ReplicateOutcome::trials).
  bool keep_trials = false;
  /// With keep_trials: the kinematic measure (analysis::kinematicsNames()) each kept trial is
  /// measured by, from its recording as it ends; empty: none (NaN).
  std::string kinematic;
  /// Where replicates' databases are made (each removed when analyzed); empty: a new folder
  /// in the system's temporary folder, removed with this object.
  std::filesystem::path scratch;
};

/// A power analysis ready to run replicates: the study and its expert prepared once.
class PowerStudy {
 public:
  /// Checks the options and the study (InputError naming what is wrong).
  explicit PowerStudy(const PowerOptions& options);
  PowerStudy(const PowerStudy&) = delete;
  PowerStudy& operator=(const PowerStudy&) = delete;

  [[nodiscard]] const report::PowerPlan& plan() const noexcept { return plan_; }
  /// Runs replicate r (0 <= r < replicates), its subjects options.threads at once.
  /// `progress` gets the fraction of its trials run.
  [[nodiscard]] report::ReplicateOutcome runReplicate(int replicate,
                                                      const std::function<void(double)>& progress = {}) const;
  /// Runs the replicates given, options.threads at once, each on a thread with its subjects one
  /// after the other (with fewer replicates than threads: one at a time, its subjects at once).
  /// The outcomes in the order given, each the same to the bit as runReplicate's. `progress`
  /// gets the replicates run so far (fractions of those under way included), one call at a time.
  [[nodiscard]] std::vector<report::ReplicateOutcome> runReplicates(
      std::span<const int> replicates, const std::function<void(double)>& progress = {}) const;
  /// The same for one design of `subjects` (per group; 3 up to the largest design): each
  /// replicate runs only that design's subjects (the first of the largest design's, so a
  /// design's outcome is the same as in runReplicates), and its outcome has that design alone.
  /// A planner's search (sim/plan.hpp) asks for designs one at a time.
  [[nodiscard]] std::vector<report::ReplicateOutcome> runDesign(
      std::span<const int> replicates, int subjects, const std::function<void(double)>& progress = {}) const;
  /// The lab time of one subject: each trial the expert's duration plus its block's rest, and
  /// `session_setup_s` for each session of the schedule [s].
  [[nodiscard]] double labSecondsPerSubject(double session_setup_s) const;
  /// Between-subjects groups (1: every subject in every strategy).
  [[nodiscard]] int groups() const noexcept { return static_cast<int>(study_.groups.size()); }

 private:
  /// How a replicate runs: its subjects at once, and the thread's paper and device (made at
  /// its first replicate, kept for the next).
  struct ReplicateRun {
    int subjects_at_once = 1;
    std::optional<session::TrialEnvironment>* environment = nullptr;
    /// The designs analyzed (ascending; the replicate runs the last one's subjects).
    std::span<const int> designs;
  };
  [[nodiscard]] std::vector<report::ReplicateOutcome> runReplicates(std::span<const int> replicates,
                                                                    std::span<const int> designs,
                                                                    const std::function<void(double)>& progress) const;
  [[nodiscard]] report::ReplicateOutcome runReplicate(int replicate, const ReplicateRun& how,
                                                      const std::function<void(double)>& progress) const;
  /// A design's outcome for each number of subjects per group, from its replicate's study.
  [[nodiscard]] report::ReplicateOutcome designOutcome(int replicate, const session::StudyDatabase& db,
                                                       const report::AnalysisOptions& options,
                                                       std::span<const int> designs) const;
  /// A design's compared trials as ReplicateOutcome::trials keeps them (kinematic NaN).
  [[nodiscard]] std::vector<report::AnalyzedTrial> analyzedTrials(
      const std::vector<const report::DesignTrialScore*>& tested) const;
  /// The replicate's subjects, `per_group` of them: the paper's (S01 ...), or per group of a
  /// design (GROUP01 ...).
  [[nodiscard]] std::vector<session::SubjectSpec> replicateSubjects(int replicate, int per_group) const;

  PowerOptions options_;
  session::StudyDefinition study_;  ///< without subjects
  nlohmann::json subject_options_;  ///< every simulated subject's options (a design: the first group's)
  std::map<std::string, nlohmann::json> group_options_;  ///< a design: each group's subjects' options
  std::string tested_phase_;        ///< a design: the phase compared
  bool between_groups_ = false;     ///< a design of several groups (else strategies within subjects)
  report::PowerPlan plan_;
  /// The scratch folder, removed when made here (also when the constructor throws).
  std::optional<ScratchFolder> scratch_;
};

}  // namespace hattr::sim
