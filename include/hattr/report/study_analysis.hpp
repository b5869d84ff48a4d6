#pragma once
/// The paper's evaluation of a study (its sections 5.1 and 6): for the analyzed recall trials
/// (10 of the 11 by default, protocol.analyzed_recall_trials), the DTW cost against the expert
/// of the shape (x, y; z reported on its own) and of the haptic profile (fx, fy, fz), from
/// analysis::TrialScorer; per metric, an ANOVA per mode with factors
/// trial and subject (the "effect of training" and the "difference between subjects"), the
/// overall mode × subject ANOVA (subject random: mode tested against mode × subject), Tukey
/// HSD between modes, per-mode mean and variance, inter-subject variance, and each subject's
/// best mode (the paper's Table 1). Offline code.

#include <array>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "hattr/analysis/anova.hpp"
#include "hattr/analysis/dtw.hpp"
#include "hattr/analysis/preprocess.hpp"
#include "hattr/analysis/trial_score.hpp"
#include "hattr/session/study_database.hpp"

namespace hattr::report {

struct AnalysisOptions {
  analysis::Normalization normalization = analysis::Normalization::kPaper;
  analysis::DtwCost cost = analysis::DtwCost::kAbsolute;
  double band_fraction = -1.0;  ///< Sakoe–Chiba band (negative: none, the paper's)
  unsigned threads = 2;
  /// Trials scored already, by trial id (a power analysis scores its replicates' trials as
  /// they end and keeps no samples): these are not read from the store.
  const std::map<std::int64_t, analysis::TrialScore>* scored = nullptr;
  /// The trial's score in `scored`, or nullptr.
  [[nodiscard]] const analysis::TrialScore* scoredAlready(std::int64_t trial_id) const {
    if (scored == nullptr) return nullptr;
    const auto it = scored->find(trial_id);
    return it == scored->end() ? nullptr : &it->second;
  }
  /// Read the kinematics of the trials in `scored` from their stored profiles too (the long
  /// table of a paper's study); a power analysis's scratch store keeps no samples to read.
  bool kinematics_of_scored = false;
  /// The metrics analyzed: a power analysis of one outcome scores only its channels, and the
  /// other metric's MetricResult is left empty (its name only).
  bool analyze_trajectory = true;
  bool analyze_force = true;
  /// Called on the calling thread as the recall trials are scored: scored so far, in all.
  std::function<void(int scored, int total)> progress;
};

/// One recall trial's costs against the expert (analysis::TrialScorer).
struct TrialCost {
  std::int64_t trial_id = 0;
  std::string subject;
  std::string mode;          ///< "BASIC", "PCONTROL", "ALPHA"
  int trial = 0;             ///< recall trial number, from 1 (a spare: the number of the trial it replaces)
  analysis::TrialScore score;
  std::string disturbed;     ///< how the loop disturbed it ("" when clean)
  [[nodiscard]] double trajectory() const { return score.shape(); }     ///< x + y
  [[nodiscard]] double forceProfile() const { return score.force(); }   ///< fx + fy + fz
};

/// A recall trial the loop disturbed, and whether the analysis kept it.
struct FlaggedTrial {
  std::int64_t trial_id = 0;
  std::string subject;
  std::string mode;
  int trial = 0;
  std::string disturbed;
  int disturbed_attempts = 0;  ///< earlier attempts kept and run again
  bool analyzed = false;
};

/// Everything computed for one metric.
struct MetricResult {
  std::string metric;                                      ///< "trajectory" or "force"
  std::map<std::string, analysis::AnovaTable> per_mode;    ///< mode -> trial × subject ANOVA
  analysis::AnovaTable overall;                            ///< mode × subject, subject random
  std::optional<analysis::TukeyResult> tukey;              ///< between modes (error: mode × subject)
  std::vector<analysis::GroupStats> per_mode_stats;        ///< mean, variance, sd per mode
  std::vector<analysis::LevelVariance> inter_subject;      ///< per mode
  std::map<std::string, std::vector<double>> mean_by_trial;  ///< mode -> mean cost per recall trial
  std::map<std::string, std::string> best_mode;            ///< subject -> mode with the lowest mean cost
};

struct StudyAnalysis {
  AnalysisOptions options;
  std::vector<std::string> modes;           ///< the study's modes in its file's order (empty: not known)
  std::vector<int> analyzed_recall_trials;  ///< the recall trial numbers used (the protocol's)
  std::string disturbed_policy;             ///< the protocol's: repeat, flag, exclude
  std::vector<FlaggedTrial> flagged;        ///< disturbed recall trials, analyzed or not
  std::vector<std::int64_t> spares_used;    ///< trials analyzed in place of excluded ones
  std::vector<TrialCost> costs;             ///< the analyzed trials
  MetricResult trajectory;
  MetricResult force;
};

/// One metric's statistics over scored recall trials (the balanced design's cells all
/// present): `trajectory` picks the shape cost, else the force cost. analyzeStudy's own, for
/// analyses of a subset of a study's trials (a power analysis's smaller designs).
MetricResult analyzeMetric(const std::string& name, const std::vector<TrialCost>& costs, bool trajectory);

/// Which analysis a study's report uses, and why in words (the report says it).
struct AnalysisChoice {
  bool balanced = false;  ///< the paper's balanced ANOVA (analyzeStudy); else the design's (analyzeDesign)
  std::string reason;
};

/// The paper's balanced ANOVA where the design is the paper's and complete with two subjects
/// or more; the design's analysis (a mixed model per phase, or one learner's progress) otherwise.
[[nodiscard]] AnalysisChoice chooseAnalysis(const session::StudyDatabase& db);
/// The same from the study's trial records as read once (db.trials()): an analysis that reads
/// them once judges one snapshot of a study that stations may be adding to.
[[nodiscard]] AnalysisChoice chooseAnalysis(const session::StudyDatabase& db,
                                            const std::vector<session::TrialRecord>& records);

/// The recall trials of a paper's study the paper's analysis takes, as far as they are
/// completed: trial id -> the recall trial number it is analyzed as. The protocol's analyzed
/// recall trials; under "exclude" a disturbed one is left out and a clean spare (a recall trial
/// outside the analyzed set, same subject and mode) takes its number where there is one. The
/// design's analysis of an incomplete paper's study analyzes these and no other recall trial.
std::map<std::int64_t, int> paperRecallTrials(const session::StudyDatabase& db);
/// The same from the study's trial records as read once (db.trials()).
std::map<std::int64_t, int> paperRecallTrials(const session::StudyDatabase& db,
                                              const std::vector<session::TrialRecord>& records);

/// Analyzes every completed recall trial. Throws InputError when the study is not complete
/// enough for the balanced design (naming the missing trials).
StudyAnalysis analyzeStudy(const session::StudyDatabase& db, const AnalysisOptions& options = {});

nlohmann::json analysisToJson(const StudyAnalysis& analysis);
/// Stores the analysis in the database (results key "analysis").
void storeAnalysis(session::StudyDatabase& db, const StudyAnalysis& analysis);
/// The per-trial costs of the analysis stored in `db` (storeAnalysis), as they were stored;
/// empty when none was. Throws InputError on a stored analysis it cannot read.
std::vector<TrialCost> storedCosts(const session::StudyDatabase& db);
/// The files writeAnalysisCsv writes (for checking outputs before any is written).
inline const std::vector<std::string> kAnalysisCsvFiles{"recall_costs.csv", "anova.csv", "table1.csv", "trials.csv"};
/// Writes recall_costs.csv, anova.csv and table1.csv into `dir` (created; existing ones replaced);
/// the caller writes trials.csv, the long table of every trial (writeTrialsCsv).
void writeAnalysisCsv(const StudyAnalysis& analysis, const std::filesystem::path& dir);

}  // namespace hattr::report
